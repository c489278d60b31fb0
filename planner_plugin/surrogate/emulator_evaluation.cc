#include "planner_plugin/surrogate/emulator_evaluation.h"

#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numeric>

#include "planner_plugin/surrogate/emulator_patient_ties.h"
#include "shape/core/error.h"
#include "shape/core/sample_statistics.h"

namespace pectus::planner {
namespace {

using Clock = std::chrono::steady_clock;

double Within(const std::vector<double>& v, double limit) {
  if (v.empty()) return 0.0;
  return static_cast<double>(std::count_if(v.begin(), v.end(), [&](double x) { return x <= limit; })) /
         static_cast<double>(v.size());
}
int WorstOf(const std::vector<double>& v, const std::vector<int>& who) {
  if (v.empty()) return -1;
  return who[static_cast<std::size_t>(std::max_element(v.begin(), v.end()) - v.begin())];
}

Eigen::MatrixXd Rows(const Eigen::MatrixXd& a, const std::vector<Eigen::Index>& keep) {
  return a(keep, Eigen::all);
}

}  // namespace

Eigen::MatrixXd EmulatorInputMatrix(const EmulatorTrainingSet& set, EmulatorInputs kind,
                                    std::vector<std::string>* names) {
  const Eigen::Index n = set.num_patients();
  Eigen::MatrixXd inputs(n, 0);
  std::vector<std::string> local;
  auto add = [&](const Eigen::VectorXd& column, const std::string& name) {
    inputs.conservativeResize(n, inputs.cols() + 1);
    inputs.rightCols(1) = column;
    local.push_back(name);
  };
  if (kind != EmulatorInputs::kMapLog) {
    if (set.ct_inputs.rows() != n || set.ct_inputs.cols() < 6)
      ThrowBadInput("emulator training set", "emulator inputs: the training set holds no CT measurements");
    for (int c = 0; c < 6; ++c) {
      const Eigen::VectorXd v = set.ct_inputs.col(c);
      if (kind != EmulatorInputs::kCt && c < 3)
        add(v.array().log().matrix(), "log_" + kCtInputNames[static_cast<std::size_t>(c)]);
      else
        add(v, kCtInputNames[static_cast<std::size_t>(c)]);
    }
  }
  if (kind == EmulatorInputs::kMapLog || kind == EmulatorInputs::kCtLogMapLog) {
    if (set.model_inputs.rows() != n || set.model_inputs.cols() < 4)
      ThrowBadInput("emulator training set",
                    "emulator inputs: the training set holds no fitted-map measurements");
    for (int c = 0; c < 3; ++c)
      add(set.model_inputs.col(c).array().log().matrix(),
          "log_" + kModelInputNames[static_cast<std::size_t>(c)]);
    add(set.model_inputs.col(3), kModelInputNames[3]);
  }
  if (!inputs.allFinite())
    ThrowBadInput("emulator training set",
                  "emulator inputs: a patient's measurement is not finite or not positive");
  if (names != nullptr) *names = std::move(local);
  return inputs;
}

void EmulatorErrors::Add(const Eigen::VectorXd& predicted, const Eigen::VectorXd& fe,
                         const Eigen::VectorXd& sd, double lift_predicted, double lift_fe, int patient) {
  if (predicted.size() != fe.size() || fe.size() % 3 != 0 || (sd.size() != 0 && sd.size() != fe.size()))
    ThrowUsage("emulator errors: predicted, FE and deviation vectors of different sizes");
  const Eigen::VectorXd e = predicted - fe;
  const Eigen::Index nv = e.size() / 3;
  std::vector<double> per_vertex(static_cast<std::size_t>(nv));
  double sum2 = 0.0;
  for (Eigen::Index v = 0; v < nv; ++v) {
    per_vertex[static_cast<std::size_t>(v)] = e.segment<3>(3 * v).norm();
    sum2 += e.segment<3>(3 * v).squaredNorm();
  }
  const double fe_norm = fe.norm();
  relative_l2_.push_back(fe_norm > 0 ? e.norm() / fe_norm : (e.norm() > 0 ? INFINITY : 0.0));
  lift_error_.push_back(std::abs(lift_predicted - lift_fe));
  patient_.push_back(patient);
  if (lift_fe <= kSmallLiftMm) {
    rms_small_.push_back(nv > 0 ? std::sqrt(sum2 / static_cast<double>(nv)) : 0.0);
    p95_small_.push_back(Quantile(per_vertex, 0.95));
    lift_error_small_.push_back(std::abs(lift_predicted - lift_fe));
    patient_small_.push_back(patient);
  }
  if (sd.size() == e.size()) {
    within_2sd_ += static_cast<double>((e.array().abs() <= 2.0 * sd.array()).count());
    coordinates_ += static_cast<double>(e.size());
  }
}

void EmulatorErrors::Merge(const EmulatorErrors& o) {
  auto append = [](auto& a, const auto& b) { a.insert(a.end(), b.begin(), b.end()); };
  append(rms_small_, o.rms_small_);
  append(p95_small_, o.p95_small_);
  append(lift_error_small_, o.lift_error_small_);
  append(patient_small_, o.patient_small_);
  append(relative_l2_, o.relative_l2_);
  append(lift_error_, o.lift_error_);
  append(patient_, o.patient_);
  within_2sd_ += o.within_2sd_;
  coordinates_ += o.coordinates_;
}

EmulatorErrors::Summary EmulatorErrors::Summarise() const {
  auto figures = [](const std::vector<double>& v, double limit) {
    return Figures{Mean(v), Quantile(v, 0.95), Max(v), limit > 0 ? Within(v, limit) : 0.0};
  };
  Summary s;
  s.cases = static_cast<std::int64_t>(relative_l2_.size());
  s.small_lift_cases = static_cast<std::int64_t>(rms_small_.size());
  s.skin_rms = figures(rms_small_, 1.0);
  s.skin_p95 = figures(p95_small_, 2.0);
  s.relative_l2 = figures(relative_l2_, 0.05);
  s.small_lift_error = figures(lift_error_small_, 1.0);
  s.lift_error = figures(lift_error_, 0.0);
  if (coordinates_ > 0) s.coverage_2sd = within_2sd_ / coordinates_;
  s.worst_skin_rms_patient = WorstOf(rms_small_, patient_small_);
  s.worst_relative_l2_patient = WorstOf(relative_l2_, patient_);
  s.worst_lift_patient = WorstOf(lift_error_, patient_);
  return s;
}

bool EmulatorEvaluationOptions::IsValid(std::string* why) const {
  std::string reason;
  if (!emulator.IsValid(&reason)) {
    if (why) *why = "emulator: " + reason;
    return false;
  }
  if (forces.empty() ||
      !std::all_of(forces.begin(), forces.end(), [](double f) { return std::isfinite(f) && f > 0; })) {
    if (why) *why = "forces must be one or more finite values > 0 N";
    return false;
  }
  return true;
}

Eigen::Index EmulatorEvaluationMinimumPatients(const EmulatorEvaluationOptions& options) {
  const Eigen::Index p = options.inputs == EmulatorInputs::kMapLog        ? 4
                         : options.inputs == EmulatorInputs::kCtLogMapLog ? 10
                                                                          : 6;
  // A linear mean has p + 1 terms and a process needs two points more than its mean has terms.
  return 1 +
         std::max<Eigen::Index>(options.emulator.min_patients, options.emulator.gp.linear_mean ? p + 3 : 3);
}

EmulatorEvaluation EvaluateEmulatorLeaveOneOut(
    const EmulatorTrainingSet& set, const EmulatorEvaluationOptions& options,
    const std::function<void(std::int64_t, std::int64_t)>& progress) {
  const auto start = Clock::now();
  std::string why;
  if (!options.IsValid(&why)) ThrowUsage("emulator evaluation: " + why);
  set.CheckShapes("emulator evaluation");
  const Eigen::Index n = set.num_patients(), q = set.num_positions(), m = 3 * set.num_skin_vertices();
  EmulatorEvaluation result;
  const Eigen::MatrixXd inputs = EmulatorInputMatrix(set, options.inputs, &result.input_names);
  const Eigen::Index needed = EmulatorEvaluationMinimumPatients(options);
  if (n < needed) {
    ThrowUsage("emulator evaluation: " + std::to_string(n) + " patients; leaving one out with " +
               std::to_string(inputs.cols()) + " inputs needs at least " + std::to_string(needed));
  }
  const bool nodes = options.through_boundary_nodes;
  if (nodes && (set.boundary_nodes.empty() || set.skin_ties.size() != static_cast<std::size_t>(n) ||
                set.lift_ties.size() != static_cast<std::size_t>(n))) {
    ThrowBadInput("emulator training set",
                  "emulator evaluation: it holds no boundary nodes and ties (build it with "
                  "boundary nodes, or learn the skin directly)");
  }
  result.folds.resize(static_cast<std::size_t>(n));
  std::vector<std::string> errors(static_cast<std::size_t>(n));
  std::int64_t done = 0;
  const int eigen_threads = Eigen::nbThreads();
  Eigen::setNbThreads(1);
#pragma omp parallel for schedule(dynamic, 1)
  for (Eigen::Index out = 0; out < n; ++out) {
    const auto o = static_cast<std::size_t>(out);
    try {
      EmulatorFold& fold = result.folds[o];
      fold.patient = set.patients[o];
      std::vector<Eigen::Index> train;
      for (Eigen::Index i = 0; i < n; ++i)
        if (i != out) train.push_back(i);
      std::vector<Eigen::MatrixXd> skin_train, learnt;
      for (Eigen::Index p = 0; p < q; ++p) {
        skin_train.push_back(Rows(set.skin[static_cast<std::size_t>(p)], train));
        learnt.push_back(nodes ? Rows(set.boundary[static_cast<std::size_t>(p)], train) : skin_train.back());
      }
      const Eigen::MatrixXd x = Rows(inputs, train), lift = Rows(set.lift_per_newton, train);
      const auto fit_start = Clock::now();
      const ResponseEmulator model(x, lift, learnt, options.emulator);
      fold.fit_seconds = std::chrono::duration<double>(Clock::now() - fit_start).count();
      fold.components = model.summary().components;
      ResponseEmulatorPrediction prediction = model.Predict(inputs.row(out).transpose());
      fold.lift_per_newton_process = prediction.lift_per_newton;
      if (nodes) prediction = ThroughTies(prediction, {set.skin_ties[o], set.lift_ties[o]});
      // The nearest training patient in standardised inputs (a constant column counts for nothing).
      const Eigen::RowVectorXd mu = x.colwise().mean();
      const Eigen::RowVectorXd sd =
          ((x.rowwise() - mu).cwiseAbs2().colwise().sum() / static_cast<double>(x.rows() - 1)).cwiseSqrt();
      Eigen::Index best = 0;
      double best_d = INFINITY;
      for (Eigen::Index j = 0; j < x.rows(); ++j) {
        double d = 0.0;
        for (Eigen::Index c = 0; c < x.cols(); ++c)
          if (sd(c) > 0) d += std::pow((x(j, c) - inputs(out, c)) / sd(c), 2);
        if (d < best_d) best_d = d, best = j;
      }
      fold.nearest_patient = set.patients[static_cast<std::size_t>(train[static_cast<std::size_t>(best)])];
      fold.lift_per_newton_fe = set.lift_per_newton.row(out).transpose();
      fold.lift_per_newton_emulator = prediction.lift_per_newton;
      const int who = static_cast<int>(out);
      for (Eigen::Index p = 0; p < q; ++p) {
        const auto pi = static_cast<std::size_t>(p);
        const Eigen::VectorXd g = set.skin[pi].row(out).transpose();
        const Eigen::VectorXd g_mean = skin_train[pi].colwise().mean().transpose();
        const Eigen::VectorXd g_near = skin_train[pi].row(best).transpose();
        if (prediction.response[pi].size() != m)
          ThrowFailure("the prediction has " + std::to_string(prediction.response[pi].size()) +
                       " skin coordinates, the set " + std::to_string(m));
        for (double f : options.forces) {
          const Eigen::VectorXd fe = f * g;
          const double lift_fe = f * set.lift_per_newton(out, p);
          fold.emulator.Add(f * prediction.response[pi], fe, f * prediction.response_sd[pi],
                            f * prediction.lift_per_newton(p), lift_fe, who);
          fold.nearest.Add(f * g_near, fe, {}, f * lift(best, p), lift_fe, who);
          fold.mean.Add(f * g_mean, fe, {}, f * lift.col(p).mean(), lift_fe, who);
        }
      }
    } catch (const std::exception& e) {
      errors[o] = e.what();
    }
#pragma omp critical(pectus_emulator_evaluation_progress)
    {
      ++done;
      if (progress) progress(done, n);
    }
  }
  Eigen::setNbThreads(eigen_threads);
  for (Eigen::Index out = 0; out < n; ++out) {
    const auto o = static_cast<std::size_t>(out);
    if (!errors[o].empty())
      ThrowFailure("emulator evaluation: patient " + set.patients[o] + " left out: " + errors[o]);
    result.emulator.Merge(result.folds[o].emulator);
    result.nearest.Merge(result.folds[o].nearest);
    result.mean.Merge(result.folds[o].mean);
  }
  result.seconds = std::chrono::duration<double>(Clock::now() - start).count();
  return result;
}

}  // namespace pectus::planner
