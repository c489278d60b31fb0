// Benchmark of the response emulator (issue 14), leaving one patient out at a time: for each patient of
// the table, the emulator fitted on the others predicts its 24 load cases (3 bar positions x 8 forces,
// DissertationLoadCases()) from its CT measurements, compared with the patient's finite element solution.
// Beside it, in the same run: the dissertation's network (OpenCV's ml::ANN_MLP, one hidden layer of 20,
// backpropagation) trained on a random 70/15/15 split of the 1488 results as the dissertation did and
// patient by patient; the nearest patient; the mean response. Prints JSON.
//
//   emulator_benchmark [--table CSV] [--cache FILE] [--patients N] [--inputs
//   map-log|ct|ct-log|ct-log+map-log]
//                      [--scale lift|norm|none] [--explained 0.9999] [--components 20] [--kernel matern|se]
//                      [--mean linear|constant] [--ann-components 10] [--ann-iterations 1000]
//                      [--ann-rate 0.01] [--no-ann] [--ann-split-only] [--target nodes|skin]
//
// What the emulator learns (--target): "nodes" (default) the responses of the mesh's boundary nodes (the
// same nodes in every patient), the skin then through the held-out patient's own ties (known from the
// fitted ribcage, without FE), its standard deviation the ties' weighted sum of the nodes' (as if their
// errors were fully correlated: the nodes of one skin vertex are neighbours); "skin" the skin grid's
// vertices directly (vertex (row, column) in every patient). With "nodes" the sternal lift too is the
// held-out patient's own linear functional of the nodes (ThroughTies, emulator_patient_ties.h: the ties
// come from the fitted ribcage alone);
// with "skin" it is the emulator's log-lift process.
//
// Inputs (the emulator's and the baselines'): "ct" the CT measurements in true size (width, depth, sternal
// length, depression, mm; torsion, degrees; the CT Haller index); "ct-log" the same with the logarithms
// of width, depth and sternal length; "map-log" the fitted patient map (log scale x, y, z, the sternum's
// depression, mm: from the fit alone, no FE; the default); "ct-log+map-log" both. The network: (a) on a
// random 70/15/15 split of the n x 24 results (the validation part unused: trained for a fixed number of
// epochs), its test figures; (b) leave one patient out; inputs the same columns plus the bar position
// (fraction) and force (N); outputs the first 10 principal-component scores of the displacement (of the
// training patients' per-newton responses, times the force) and the sternal lift; OpenCV scales inputs
// and outputs; symmetric sigmoid; BACKPROP, weight-gradient scale 0.01, momentum 0.1, 1000 epochs.
//
// Metrics (the skin grid's vertices; u the displacement of a load case, mm):
//  - per case: the per-vertex Euclidean error e_v = |u_pred,v - u_fe,v|, its RMS over the vertices and its
//    95th percentile; the relative L2 error |u_pred - u_fe| / |u_fe| over all coordinates; the sternal
//    lift's error |lift_pred - lift_fe|;
//  - skin RMS and p95 on the cases whose FE sternal lift is <= 40 mm, relative L2 on all cases, the
//    lift error on both;
//  - 2 sigma coverage (emulator): the fraction of all output coordinates of all cases (3 #vertices x 24
//    x #patients) whose error lies within twice the predicted standard deviation.
#include <omp.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <numeric>
#include <opencv2/core.hpp>
#include <opencv2/ml.hpp>
#include <random>
#include <string>
#include <vector>

#include "planner_plugin/ribcage/ribcage_fem.h"
#include "planner_plugin/surrogate/emulator_evaluation.h"
#include "planner_plugin/surrogate/emulator_training_set.h"
#include "planner_plugin/surrogate/response_emulator.h"
#include "shape/core/error.h"
#include "shape/core/sample_statistics.h"
#include "shape/io/patient_table_io.h"
#include "tests/support/shared_data.h"

namespace {

using namespace pectus::planner;
using pectus::Max;
using pectus::Mean;
using pectus::Quantile;
using Clock = std::chrono::steady_clock;

double Seconds(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

// The figures of one method over its test cases (EmulatorErrors, emulator_evaluation.h), as JSON.
nlohmann::json Json(const EmulatorErrors& errors) {
  const EmulatorErrors::Summary s = errors.Summarise();
  nlohmann::json j = {{"cases", s.cases},
                      {"cases_lift_le_40mm", s.small_lift_cases},
                      {"skin_rms_mm_lift_le_40",
                       {{"mean", s.skin_rms.mean},
                        {"p95", s.skin_rms.p95},
                        {"max", s.skin_rms.max},
                        {"fraction_le_1mm", s.skin_rms.within}}},
                      {"skin_p95_mm_lift_le_40",
                       {{"mean", s.skin_p95.mean},
                        {"p95", s.skin_p95.p95},
                        {"max", s.skin_p95.max},
                        {"fraction_le_2mm", s.skin_p95.within}}},
                      {"relative_l2_all",
                       {{"mean", s.relative_l2.mean},
                        {"p95", s.relative_l2.p95},
                        {"max", s.relative_l2.max},
                        {"fraction_le_5pc", s.relative_l2.within}}},
                      {"lift_error_mm_lift_le_40",
                       {{"mean", s.small_lift_error.mean},
                        {"p95", s.small_lift_error.p95},
                        {"max", s.small_lift_error.max},
                        {"fraction_le_1mm", s.small_lift_error.within}}},
                      {"lift_error_mm_all",
                       {{"mean", s.lift_error.mean}, {"p95", s.lift_error.p95}, {"max", s.lift_error.max}}}};
  if (s.coverage_2sd >= 0) j["coverage_2sd"] = s.coverage_2sd;
  return j;
}

// The first n patients of `set`.
EmulatorTrainingSet FirstPatients(const EmulatorTrainingSet& set, Eigen::Index n) {
  EmulatorTrainingSet first = set;
  first.patients.resize(static_cast<std::size_t>(n));
  first.ct_inputs = set.ct_inputs.topRows(n);
  first.model_inputs = set.model_inputs.topRows(n);
  first.lift_per_newton = set.lift_per_newton.topRows(n);
  first.skin_anchor_generic_mm = set.skin_anchor_generic_mm.topRows(n);
  for (auto* arrays : {&first.skin, &first.bone, &first.boundary})
    for (Eigen::MatrixXd& a : *arrays) a = Eigen::MatrixXd(a.topRows(n));
  if (!first.skin_ties.empty()) first.skin_ties.resize(static_cast<std::size_t>(n));
  if (!first.lift_ties.empty()) first.lift_ties.resize(static_cast<std::size_t>(n));
  return first;
}

// The dissertation's network: inputs (patient parameters, position, force), outputs the first `k`
// principal-component scores of the displacement plus the sternal lift, one hidden layer of 20, BACKPROP.
class AnnBaseline {
 public:
  // `cases`: (patient, position index, force) triples to train on; `basis_patients`: whose per-newton
  // responses define the components.
  AnnBaseline(const EmulatorTrainingSet& set, const Eigen::MatrixXd& inputs,
              const std::vector<double>& forces, const std::vector<std::array<int, 2>>& cases,
              const std::vector<Eigen::Index>& basis_patients, int k, int iterations, double rate,
              unsigned seed)
      : set_(set), inputs_(inputs) {
    const Eigen::Index q = set.num_positions(), m = 3 * set.num_skin_vertices();
    // Components of the per-newton responses (patient x position rows): u = F (mean + V t).
    Eigen::MatrixXd g(static_cast<Eigen::Index>(basis_patients.size()) * q, m);
    for (std::size_t i = 0; i < basis_patients.size(); ++i)
      for (Eigen::Index p = 0; p < q; ++p)
        g.row(static_cast<Eigen::Index>(i) * q + p) = set.skin[p].row(basis_patients[i]);
    mean_ = g.colwise().mean().transpose();
    const Eigen::MatrixXd c = g.rowwise() - mean_.transpose();
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(c * c.transpose());
    const Eigen::Index r = eig.eigenvalues().size();
    k = static_cast<int>(std::min<Eigen::Index>(k, r));
    modes_.resize(m, k);
    double kept = 0.0;
    for (int j = 0; j < k; ++j) {
      const double lambda = eig.eigenvalues()(r - 1 - j);
      modes_.col(j) = c.transpose() * eig.eigenvectors().col(r - 1 - j) / std::sqrt(lambda);
      kept += lambda;
    }
    explained_ = kept / eig.eigenvalues().sum();
    // Training samples.
    cv::Mat x(static_cast<int>(cases.size()), static_cast<int>(inputs.cols()) + 2, CV_32F);
    cv::Mat y(static_cast<int>(cases.size()), k + 1, CV_32F);
    for (std::size_t s = 0; s < cases.size(); ++s) {
      const int i = cases[s][0] / static_cast<int>(q), p = cases[s][0] % static_cast<int>(q);
      const double f = forces[static_cast<std::size_t>(cases[s][1])];
      Row(i, p, f, x.ptr<float>(static_cast<int>(s)));
      const Eigen::VectorXd t = modes_.transpose() * (set.skin[p].row(i).transpose() - mean_);
      for (int j = 0; j < k; ++j) y.at<float>(static_cast<int>(s), j) = static_cast<float>(f * t(j));
      y.at<float>(static_cast<int>(s), k) = static_cast<float>(f * set.lift_per_newton(i, p));
    }
    cv::theRNG().state = seed;
    ann_ = cv::ml::ANN_MLP::create();
    const cv::Mat layers = (cv::Mat_<int>(3, 1) << x.cols, 20, y.cols);
    ann_->setLayerSizes(layers);
    ann_->setActivationFunction(cv::ml::ANN_MLP::SIGMOID_SYM, 1.0, 1.0);
    ann_->setTrainMethod(cv::ml::ANN_MLP::BACKPROP, rate, 0.1);
    ann_->setTermCriteria(
        cv::TermCriteria(cv::TermCriteria::MAX_ITER + cv::TermCriteria::EPS, iterations, 1e-9));
    ann_->train(cv::ml::TrainData::create(x, cv::ml::ROW_SAMPLE, y));
  }

  // Predicted displacement (3 #vertices, mm) and lift (mm) of patient i's case (position p, force f).
  Eigen::VectorXd Predict(int i, int p, double f, double* lift) const {
    cv::Mat x(1, static_cast<int>(inputs_.cols()) + 2, CV_32F), y;
    Row(i, p, f, x.ptr<float>(0));
    ann_->predict(x, y);
    Eigen::VectorXd t(modes_.cols());
    for (Eigen::Index j = 0; j < t.size(); ++j) t(j) = y.at<float>(0, static_cast<int>(j));
    *lift = y.at<float>(0, static_cast<int>(t.size()));
    return f * mean_ + modes_ * t;
  }
  double explained() const { return explained_; }

 private:
  void Row(int i, int p, double f, float* out) const {
    for (Eigen::Index d = 0; d < inputs_.cols(); ++d) out[d] = static_cast<float>(inputs_(i, d));
    out[inputs_.cols()] = static_cast<float>(set_.positions(p));
    out[inputs_.cols() + 1] = static_cast<float>(f);
  }
  const EmulatorTrainingSet& set_;
  const Eigen::MatrixXd& inputs_;
  Eigen::VectorXd mean_;
  Eigen::MatrixXd modes_;
  double explained_ = 0.0;
  cv::Ptr<cv::ml::ANN_MLP> ann_;
};

// Whether skin vertex (row, column) is the same anatomical point in every patient: the spread across
// patients of where its ties sit on the generic ribcage, against the grid's spacing there.
nlohmann::json CorrespondenceCheck(const EmulatorTrainingSet& set) {
  const Eigen::Index nv = set.num_skin_vertices(), n = set.num_patients();
  std::vector<double> spread, spacing;
  const Eigen::RowVectorXd mean = set.skin_anchor_generic_mm.colwise().mean();
  for (Eigen::Index v = 0; v < nv; ++v) {
    double s2 = 0.0;
    for (Eigen::Index i = 0; i < n; ++i)
      s2 += (set.skin_anchor_generic_mm.block(i, 3 * v, 1, 3) - mean.segment(3 * v, 3)).squaredNorm();
    spread.push_back(std::sqrt(s2 / static_cast<double>(n)));
    if ((v + 1) % set.skin_columns != 0)
      spacing.push_back((mean.segment(3 * v + 3, 3) - mean.segment(3 * v, 3)).norm());
    if (v + set.skin_columns < nv)
      spacing.push_back((mean.segment(3 * (v + set.skin_columns), 3) - mean.segment(3 * v, 3)).norm());
  }
  return {{"what",
           "per skin vertex, the RMS over patients of the distance of its ties' point on the generic ribcage "
           "from their mean (mm), against the spacing of neighbouring vertices there"},
          {"spread_mm",
           {{"median", Quantile(spread, 0.5)}, {"p95", Quantile(spread, 0.95)}, {"max", Max(spread)}}},
          {"grid_spacing_mm_median", Quantile(spacing, 0.5)}};
}

}  // namespace

int main(int argc, char** argv) {
  std::string table, cache, inputs_kind = "map-log";
  int patients = 0, ann_components = 10, ann_iterations = 1000;
  bool ann = true, split_only = false;
  std::string target = "nodes";
  double ann_rate = 0.01;
  ResponseEmulatorOptions options;
  const char* usage =
      "usage: emulator_benchmark [--table CSV] [--cache FILE] [--patients N] "
      "[--inputs map-log|ct|ct-log|ct-log+map-log] [--scale lift|norm|none] [--explained 0.9999] "
      "[--components 20] "
      "[--kernel matern|se] [--mean linear|constant] [--ann-components 10] "
      "[--ann-iterations 1000] [--ann-rate 0.01] [--no-ann] [--ann-split-only] [--target nodes|skin]\n";
  try {
    for (int i = 1; i < argc; ++i) {
      const std::string a = argv[i];
      auto next = [&]() -> std::string {
        if (i + 1 >= argc) throw std::runtime_error(a + " needs a value");
        return argv[++i];
      };
      if (a == "--table")
        table = next();
      else if (a == "--cache")
        cache = next();
      else if (a == "--patients")
        patients = std::stoi(next());
      else if (a == "--inputs")
        inputs_kind = next();
      else if (a == "--explained")
        options.explained_fraction = std::stod(next());
      else if (a == "--components")
        options.max_components = std::stoi(next());
      else if (a == "--scale") {
        const std::string v = next();
        if (v != "lift" && v != "norm" && v != "none")
          throw std::runtime_error("--scale is lift, norm or none");
        options.scale = v == "lift"   ? ResponseScale::kLift
                        : v == "none" ? ResponseScale::kNone
                                      : ResponseScale::kNorm;
      } else if (a == "--kernel")
        options.gp.kernel = next() == "se" ? GpKernel::kSquaredExponential : GpKernel::kMatern52;
      else if (a == "--mean")
        options.gp.linear_mean = next() == "linear";
      else if (a == "--ann-components")
        ann_components = std::stoi(next());
      else if (a == "--ann-iterations")
        ann_iterations = std::stoi(next());
      else if (a == "--no-ann")
        ann = false;
      else if (a == "--ann-rate")
        ann_rate = std::stod(next());
      else if (a == "--ann-split-only")
        split_only = true;
      else if (a == "--target")
        target = next();
      else {
        std::cerr << usage;
        return 2;
      }
    }
    if (inputs_kind != "ct" && inputs_kind != "ct-log" && inputs_kind != "map-log" &&
        inputs_kind != "ct-log+map-log")
      throw std::runtime_error("--inputs is ct, ct-log, map-log or ct-log+map-log");
    if (table.empty()) table = pectus::testing_support::SharedPath(pectus::testing_support::kPatientTable);
    nlohmann::json report;
    report["benchmark"] = "emulator";
    report["command"] = std::string(argv[0]);
    for (int i = 1; i < argc; ++i) report["command"] = report["command"].get<std::string>() + " " + argv[i];
    report["threads"] = omp_get_max_threads();
    report["ann"] = {
        {"hidden", 20}, {"components", ann_components}, {"epochs", ann_iterations}, {"rate", ann_rate}};
    std::vector<pectus::PatientTableRow> rows = pectus::ReadPatientTable(table);
    if (patients > 0 && patients < static_cast<int>(rows.size()))
      rows.resize(static_cast<std::size_t>(patients));

    // The training set: from the cache when it holds these patients, else solved (and cached).
    auto start = Clock::now();
    EmulatorTrainingSet set;
    bool cached = false;
    if (!cache.empty() && std::filesystem::exists(cache)) {
      set = LoadEmulatorTrainingSet(cache);
      cached = set.num_patients() >= static_cast<Eigen::Index>(rows.size());
      for (std::size_t i = 0; cached && i < rows.size(); ++i)
        cached = set.patients[i] == std::to_string(rows[i].patient);
      if (!cached)
        std::fprintf(stderr, "emulator_benchmark: %s holds other patients; solving again\n", cache.c_str());
    }
    if (!cached) {
      set = BuildEmulatorTrainingSet(rows, {}, [](std::int64_t done, std::int64_t total) {
        std::fprintf(stderr, "emulator_benchmark: FE %lld / %lld\n", static_cast<long long>(done),
                     static_cast<long long>(total));
      });
      if (!cache.empty()) SaveEmulatorTrainingSet(set, cache);
      report["training_set_timings_s"] = {{"fit", set.timings_s.Seconds("fit")},
                                          {"fem", set.timings_s.Seconds("fem")},
                                          {"skin", set.timings_s.Seconds("skin")}};
    }
    report["training_set"] = {{"from_cache", cached},
                              {"seconds", Seconds(start)},
                              {"patients", rows.size()},
                              {"skin_vertices", set.num_skin_vertices()},
                              {"positions", set.positions}};
    report["correspondence"] = CorrespondenceCheck(set);
    if (target != "nodes" && target != "skin") throw std::runtime_error("--target is nodes or skin");
    if (target == "nodes" && set.boundary_nodes.empty())
      throw std::runtime_error(
          "the training set holds no boundary nodes (--target skin, or rebuild the cache)");
    using Rows3 = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;
    const auto nbn = static_cast<Eigen::Index>(set.boundary_nodes.size());
    // Skin coordinates (3 #skin vertices) of boundary-node values (3 #boundary nodes) through patient i's
    // ties.
    auto to_skin = [&](Eigen::Index i, const Eigen::VectorXd& nodes) -> Eigen::VectorXd {
      const Rows3 skin =
          set.skin_ties[static_cast<std::size_t>(i)] * Eigen::Map<const Rows3>(nodes.data(), nbn, 3);
      return Eigen::Map<const Eigen::VectorXd>(skin.data(), skin.size());
    };
    if (nbn > 0) {
      double worst = 0.0;
      for (Eigen::Index i = 0; i < set.num_patients(); ++i)
        for (Eigen::Index p = 0; p < set.num_positions(); ++p)
          worst = std::max(worst,
                           (to_skin(i, set.boundary[p].row(i).transpose()) - set.skin[p].row(i).transpose())
                               .cwiseAbs()
                               .maxCoeff());
      double worst_lift = 0.0;
      for (Eigen::Index i = 0; i < set.num_patients(); ++i)
        for (Eigen::Index p = 0; p < set.num_positions(); ++p)
          worst_lift = std::max(worst_lift, std::abs((set.lift_ties[static_cast<std::size_t>(i)] *
                                                      set.boundary[p].row(i).transpose())(0) -
                                                     set.lift_per_newton(i, p)));
      report["training_set"]["lift_from_ties_max_difference_mm_per_n"] = worst_lift;
      report["training_set"]["boundary_nodes"] = nbn;
      report["training_set"]["skin_from_ties_max_difference_mm_per_n"] = worst;
    }

    const auto n = static_cast<Eigen::Index>(rows.size());
    if (set.num_patients() > n) set = FirstPatients(set, n);
    const Eigen::Index q = set.num_positions();
    EmulatorEvaluationOptions evaluation;
    evaluation.emulator = options;
    evaluation.inputs = inputs_kind == "ct"        ? EmulatorInputs::kCt
                        : inputs_kind == "ct-log"  ? EmulatorInputs::kCtLog
                        : inputs_kind == "map-log" ? EmulatorInputs::kMapLog
                                                   : EmulatorInputs::kCtLogMapLog;
    evaluation.through_boundary_nodes = target == "nodes";
    std::vector<std::string> input_names;
    const Eigen::MatrixXd inputs = EmulatorInputMatrix(set, evaluation.inputs, &input_names);
    report["inputs"] = input_names;
    const std::vector<double>& forces = evaluation.forces;  // the dissertation's eight
    const auto nf = static_cast<int>(forces.size());

    // Leave one patient out: the emulator, the nearest patient and the mean response (the library's
    // evaluation, as `pectus surrogate evaluate`), then the network on the same folds.
    EmulatorEvaluation loo;
    if (!split_only) {
      loo = EvaluateEmulatorLeaveOneOut(set, evaluation, [&](std::int64_t done, std::int64_t total) {
        std::fprintf(stderr, "emulator_benchmark: %lld / %lld patients left out\n",
                     static_cast<long long>(done), static_cast<long long>(total));
      });
    }
    nlohmann::json per_patient = nlohmann::json::array();
    std::vector<double> fit_s, components;
    std::vector<EmulatorErrors> fold_ann(static_cast<std::size_t>(n));
    std::vector<double> fold_explained_ann(static_cast<std::size_t>(n));
    std::vector<std::string> fold_error(static_cast<std::size_t>(n));
    Eigen::setNbThreads(1);
#pragma omp parallel for schedule(dynamic, 1)
    for (Eigen::Index out = 0; out < (split_only || !ann ? 0 : n); ++out) {
      const auto o = static_cast<std::size_t>(out);
      try {
        std::vector<Eigen::Index> train;
        for (Eigen::Index i = 0; i < n; ++i)
          if (i != out) train.push_back(i);
        std::vector<std::array<int, 2>> cases;
        for (Eigen::Index i : train)
          for (Eigen::Index p = 0; p < q; ++p)
            for (int f = 0; f < nf; ++f) cases.push_back({static_cast<int>(i * q + p), f});
        const AnnBaseline network(set, inputs, forces, cases, train, ann_components, ann_iterations, ann_rate,
                                  1400u + static_cast<unsigned>(out));
        fold_explained_ann[o] = network.explained();
        for (Eigen::Index p = 0; p < q; ++p) {
          for (double f : forces) {
            double l = 0.0;
            const Eigen::VectorXd u = network.Predict(static_cast<int>(out), static_cast<int>(p), f, &l);
            fold_ann[o].Add(u, f * set.skin[p].row(out).transpose(), {}, l, f * set.lift_per_newton(out, p),
                            static_cast<int>(out));
          }
        }
      } catch (const std::exception& e) {
        fold_error[o] = e.what();
      }
    }
    EmulatorErrors ann_loo;
    for (std::size_t o = 0; o < loo.folds.size(); ++o) {
      if (!fold_error[o].empty())
        throw std::runtime_error("patient " + set.patients[o] + " left out: " + fold_error[o]);
      ann_loo.Merge(fold_ann[o]);
      const EmulatorFold& fold = loo.folds[o];
      fit_s.push_back(fold.fit_seconds);
      for (int c : fold.components) components.push_back(c);
      nlohmann::json pj = Json(fold.emulator);
      pj["patient"] = fold.patient;
      pj["lift_per_newton_fe"] =
          std::vector<double>(fold.lift_per_newton_fe.begin(), fold.lift_per_newton_fe.end());
      pj["lift_per_newton_emulator"] =
          std::vector<double>(fold.lift_per_newton_emulator.begin(), fold.lift_per_newton_emulator.end());
      pj["lift_per_newton_process"] =
          std::vector<double>(fold.lift_per_newton_process.begin(), fold.lift_per_newton_process.end());
      pj["nearest_patient"] = fold.nearest_patient;
      if (ann) pj["ann_relative_l2_mean"] = fold_ann[o].Summarise().relative_l2.mean;
      per_patient.push_back(pj);
    }
    const double explained_ann = Mean(fold_explained_ann);
    report["emulator_options"] = {
        {"target", target},
        {"kernel", options.gp.kernel == GpKernel::kMatern52 ? "matern52" : "squared_exponential"},
        {"linear_mean", options.gp.linear_mean},
        {"explained_fraction", options.explained_fraction},
        {"max_components", options.max_components},
        {"scale", options.scale == ResponseScale::kNorm   ? "norm"
                  : options.scale == ResponseScale::kLift ? "lift"
                                                          : "none"}};
    nlohmann::json methods;
    methods["emulator_loo"] = Json(loo.emulator);
    methods["emulator_loo"]["fit_s_mean"] = Mean(fit_s);
    {
      // The lift error on the cases within the linear model's range, where an FE answer is a prediction:
      // a lift of at most twice the depression and at least 20 mm (the planner's flag, LinearRangeLiftMm).
      std::vector<double> errors;
      for (std::size_t o = 0; o < loo.folds.size(); ++o) {
        const EmulatorFold& fold = loo.folds[o];
        const double limit = std::max(2.0 * set.ct_inputs(static_cast<Eigen::Index>(o), 3), 20.0);
        for (Eigen::Index p = 0; p < fold.lift_per_newton_fe.size(); ++p)
          for (double f : forces)
            if (f * fold.lift_per_newton_fe(p) <= limit)
              errors.push_back(f * std::abs(fold.lift_per_newton_emulator(p) - fold.lift_per_newton_fe(p)));
      }
      const auto within = std::count_if(errors.begin(), errors.end(), [](double e) { return e <= 1.0; });
      methods["emulator_loo"]["lift_error_mm_linear_range"] = {
          {"cases", errors.size()},
          {"mean", Mean(errors)},
          {"max", Max(errors)},
          {"fraction_le_1mm",
           errors.empty() ? 0.0 : static_cast<double>(within) / static_cast<double>(errors.size())}};
    }
    methods["emulator_loo"]["components_mean"] = Mean(components);
    methods["nearest_patient_loo"] = Json(loo.nearest);
    methods["mean_response_loo"] = Json(loo.mean);
    if (ann) {
      methods["ann_loo"] = Json(ann_loo);
      methods["ann_loo"]["explained_by_components"] = explained_ann;

      // The dissertation's split: the n x 24 results shuffled, 70 % training, 15 % validation, 15 % test.
      std::vector<std::array<int, 2>> all;
      for (Eigen::Index i = 0; i < n; ++i)
        for (Eigen::Index p = 0; p < q; ++p)
          for (int f = 0; f < nf; ++f) all.push_back({static_cast<int>(i * q + p), f});
      std::mt19937 rng(1488);
      std::shuffle(all.begin(), all.end(), rng);
      const std::size_t n_train = all.size() * 70 / 100, n_valid = all.size() * 15 / 100;
      const std::vector<std::array<int, 2>> training(all.begin(),
                                                     all.begin() + static_cast<std::ptrdiff_t>(n_train));
      std::vector<Eigen::Index> everyone(static_cast<std::size_t>(n));
      std::iota(everyone.begin(), everyone.end(), 0);
      const AnnBaseline network(set, inputs, forces, training, everyone, ann_components, ann_iterations,
                                ann_rate, 1488u);
      EmulatorErrors random_split;
      for (std::size_t s = n_train + n_valid; s < all.size(); ++s) {
        const int i = all[s][0] / static_cast<int>(q), p = all[s][0] % static_cast<int>(q);
        const double f = forces[static_cast<std::size_t>(all[s][1])];
        double l = 0.0;
        const Eigen::VectorXd u = network.Predict(i, p, f, &l);
        random_split.Add(u, f * set.skin[p].row(i).transpose(), {}, l, f * set.lift_per_newton(i, p), i);
      }
      methods["ann_random_split_test"] = Json(random_split);
      methods["ann_random_split_test"]["split"] = {
          {"training", n_train}, {"validation_unused", n_valid}, {"test", all.size() - n_train - n_valid}};
    }
    report["methods"] = methods;
    report["per_patient_emulator"] = per_patient;
    std::cout << report.dump(2) << "\n";
  } catch (const std::exception& e) {
    std::cerr << "emulator_benchmark: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
