#include "planner_plugin/surrogate/response_emulator.h"

#include <Eigen/Eigenvalues>
#include <chrono>
#include <cmath>
#include <cstdio>

#include "shape/core/error.h"

namespace pectus::planner {

bool ResponseEmulatorOptions::IsValid(std::string* why) const {
  std::string reason;
  if (!gp.IsValid(&reason)) {
    if (why) *why = "response emulator: " + reason;
    return false;
  }
  auto fail = [&](const char* text) {
    if (why) *why = text;
    return false;
  };
  if (!(explained_fraction > 0.0 && explained_fraction <= 1.0))
    return fail("response emulator: explained_fraction must be in (0, 1]");
  if (max_components < 1) return fail("response emulator: max_components must be >= 1");
  if (min_patients < 4) return fail("response emulator: min_patients must be >= 4");
  return true;
}

struct ResponseEmulator::Position {
  std::unique_ptr<GaussianProcess> log_lift;
  std::unique_ptr<GaussianProcess> log_norm;  // kNorm only
  std::vector<GaussianProcess> scores;        // per component
  Eigen::VectorXd mean;                       // m: the mean shape
  Eigen::MatrixXd modes;                      // m by K, orthonormal columns
  Eigen::VectorXd residual_var;               // m: the leave-one-out projection residual's variance
};

namespace {

// Eigen-decomposition of a symmetric matrix, eigenvalues descending (clamped at 0).
void Descending(const Eigen::MatrixXd& g, Eigen::VectorXd* values, Eigen::MatrixXd* vectors) {
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(g);
  *values = eig.eigenvalues().reverse().cwiseMax(0.0);
  *vectors = eig.eigenvectors().rowwise().reverse();
}

// Per output coordinate, the mean over patients of the squared residual of each patient's row of `s`
// (n by m) projected onto the first `k` principal components of the other rows (centered on their mean):
// what k modes of n - 1 patients cannot represent of a new one. From the Gram matrix `gram` = s s'.
Eigen::VectorXd LeaveOneOutResidualVariance(const Eigen::MatrixXd& s, const Eigen::MatrixXd& gram, int k) {
  const Eigen::Index n = s.rows(), no = n - 1;
  Eigen::VectorXd out = Eigen::VectorXd::Zero(s.cols());
  Eigen::MatrixXd centering = Eigen::MatrixXd::Identity(no, no);
  centering.array() -= 1.0 / static_cast<double>(no);
  for (Eigen::Index i = 0; i < n; ++i) {
    std::vector<Eigen::Index> others;
    for (Eigen::Index j = 0; j < n; ++j)
      if (j != i) others.push_back(j);
    const Eigen::MatrixXd g_oo = gram(others, others);
    const Eigen::VectorXd g_oi = gram(others, i);
    Eigen::VectorXd values;
    Eigen::MatrixXd vectors;
    Descending(centering * g_oo * centering, &values, &vectors);
    // b = Xo (s_i - mean of the others), c = W L^-1 W' b over the kept components.
    const Eigen::VectorXd b =
        centering * (g_oi - g_oo * Eigen::VectorXd::Constant(no, 1.0 / static_cast<double>(no)));
    Eigen::VectorXd c = Eigen::VectorXd::Zero(no);
    for (int j = 0; j < k && j < no; ++j) {
      if (values(j) <= 1e-12 * values(0)) break;
      c += vectors.col(j) * (vectors.col(j).dot(b) / values(j));
    }
    // residual = s_i - S_o' (1 / no + P c), as a combination of the rows of s.
    Eigen::VectorXd coefficients = Eigen::VectorXd::Zero(n);
    coefficients(i) = 1.0;
    const Eigen::VectorXd w = (centering * c).array() + 1.0 / static_cast<double>(no);
    for (Eigen::Index j = 0; j < no; ++j) coefficients(others[static_cast<std::size_t>(j)]) = -w(j);
    out += (s.transpose() * coefficients).cwiseAbs2();
  }
  return out / static_cast<double>(n);
}

}  // namespace

ResponseEmulator::ResponseEmulator(const Eigen::MatrixXd& inputs, const Eigen::MatrixXd& lift_per_newton,
                                   const std::vector<Eigen::MatrixXd>& responses,
                                   const ResponseEmulatorOptions& options)
    : options_(options) {
  const auto start = std::chrono::steady_clock::now();
  std::string why;
  if (!options.IsValid(&why)) ThrowUsage(why);
  const Eigen::Index n = inputs.rows(), q = lift_per_newton.cols();
  if (n < options.min_patients)
    ThrowUsage("response emulator: " + std::to_string(n) + " patients, at least " +
               std::to_string(options.min_patients) + " needed");
  if (lift_per_newton.rows() != n)
    ThrowUsage("response emulator: " + std::to_string(n) + " rows of inputs but " +
               std::to_string(lift_per_newton.rows()) + " rows of lifts");
  if (q < 1 || static_cast<Eigen::Index>(responses.size()) != q)
    ThrowUsage("response emulator: " + std::to_string(q) + " positions of lifts but " +
               std::to_string(responses.size()) + " response matrices");
  if (!inputs.allFinite()) ThrowUsage("response emulator: an input is not finite");
  if (!lift_per_newton.allFinite() || !(lift_per_newton.array() > 0.0).all())
    ThrowUsage("response emulator: every sternal lift per newton must be finite and > 0");
  num_inputs_ = inputs.cols();
  num_outputs_ = responses.front().cols();
  for (std::size_t k = 0; k < responses.size(); ++k) {
    if (responses[k].rows() != n || responses[k].cols() != num_outputs_ || num_outputs_ < 1)
      ThrowUsage("response emulator: the responses at position " + std::to_string(k) + " are " +
                 std::to_string(responses[k].rows()) + " by " + std::to_string(responses[k].cols()) +
                 ", not " + std::to_string(n) + " by " + std::to_string(num_outputs_));
    if (!responses[k].allFinite())
      ThrowUsage("response emulator: a response at position " + std::to_string(k) + " is not finite");
  }
  Eigen::MatrixXd centering = Eigen::MatrixXd::Identity(n, n);
  centering.array() -= 1.0 / static_cast<double>(n);
  for (Eigen::Index k = 0; k < q; ++k) {
    auto p = std::make_unique<Position>();
    // The log sternal lift per newton.
    p->log_lift =
        std::make_unique<GaussianProcess>(inputs, lift_per_newton.col(k).array().log().matrix(), options.gp);
    // The shapes: responses divided by their scale.
    Eigen::MatrixXd s = responses[static_cast<std::size_t>(k)];
    if (options.scale == ResponseScale::kLift) s = lift_per_newton.col(k).cwiseInverse().asDiagonal() * s;
    if (options.scale == ResponseScale::kNorm) {
      const Eigen::VectorXd norm = s.rowwise().norm();
      if (!(norm.array() > 0.0).all()) ThrowUsage("response emulator: a response is zero everywhere");
      p->log_norm = std::make_unique<GaussianProcess>(inputs, norm.array().log().matrix(), options.gp);
      s = norm.cwiseInverse().asDiagonal() * s;
      summary_.scale_gp.push_back(p->log_norm->summary());
    }
    // Principal components through the Gram matrix (n is small, m large).
    const Eigen::MatrixXd gram = s * s.transpose();
    Eigen::VectorXd values;
    Eigen::MatrixXd vectors;
    Descending(centering * gram * centering, &values, &vectors);
    const double total = values.sum();
    int kept = 0;
    double explained = 0.0;
    const int most = static_cast<int>(std::min<Eigen::Index>(options.max_components, n - 2));
    while (kept < most && values(kept) > 1e-12 * values(0) && explained < options.explained_fraction * total)
      explained += values(kept++);
    p->mean = s.colwise().mean().transpose();
    const Eigen::MatrixXd centred = s.rowwise() - p->mean.transpose();
    p->modes.resize(num_outputs_, kept);
    for (int j = 0; j < kept; ++j) {
      p->modes.col(j) = centred.transpose() * vectors.col(j) / std::sqrt(values(j));
      // The component's scores: W sqrt(lambda).
      p->scores.emplace_back(inputs, vectors.col(j) * std::sqrt(values(j)), options.gp);
    }
    p->residual_var = LeaveOneOutResidualVariance(s, gram, kept);
    summary_.components.push_back(kept);
    summary_.explained.push_back(total > 0.0 ? explained / total : 1.0);
    summary_.residual_rms.push_back(std::sqrt(p->residual_var.mean()));
    summary_.lift_gp.push_back(p->log_lift->summary());
    positions_.push_back(std::move(p));
  }
  summary_.fit_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::string components;
  for (int c : summary_.components) components += (components.empty() ? "" : ", ") + std::to_string(c);
  char text[160];
  std::snprintf(text, sizeof(text),
                "%lld patients, %lld positions, components per position: ", static_cast<long long>(n),
                static_cast<long long>(q));
  summary_.message = text + components;
}

ResponseEmulator::~ResponseEmulator() = default;
ResponseEmulator::ResponseEmulator(ResponseEmulator&&) noexcept = default;

ResponseEmulatorPrediction ResponseEmulator::Predict(const Eigen::VectorXd& x) const {
  if (x.size() != num_inputs_)
    ThrowUsage("response emulator: a patient of " + std::to_string(x.size()) +
               " parameters, the emulator has " + std::to_string(num_inputs_));
  const auto q = static_cast<Eigen::Index>(positions_.size());
  ResponseEmulatorPrediction out;
  out.lift_per_newton.resize(q);
  out.lift_sd.resize(q);
  for (Eigen::Index k = 0; k < q; ++k) {
    const Position& p = *positions_[static_cast<std::size_t>(k)];
    double log_sd = 0.0;
    const double lift = std::exp(p.log_lift->Predict(x, nullptr, &log_sd));
    // The log-normal's variance about its median, L^2 (exp(s^2) - 1) (close to (L s)^2).
    const double lift_var = lift * lift * std::expm1(log_sd * log_sd);
    out.lift_per_newton(k) = lift;
    out.lift_sd(k) = std::sqrt(lift_var);
    Eigen::VectorXd t(p.modes.cols()), t_var(p.modes.cols());
    for (Eigen::Index j = 0; j < t.size(); ++j) {
      double sd = 0.0;
      t(j) = p.scores[static_cast<std::size_t>(j)].Predict(x, nullptr, &sd);
      t_var(j) = sd * sd;
    }
    Eigen::VectorXd shape = p.mean + p.modes * t;
    Eigen::VectorXd shape_var = p.modes.cwiseAbs2() * t_var + p.residual_var;
    double scale = 1.0, scale_var = 0.0;
    if (options_.scale == ResponseScale::kLift) scale = lift, scale_var = lift_var;
    if (options_.scale == ResponseScale::kNorm) {
      double sd = 0.0;
      scale = std::exp(p.log_norm->Predict(x, nullptr, &sd));
      scale_var = scale * scale * std::expm1(sd * sd);
    }
    // u = c s: var = c^2 var(s) + s^2 var(c) + var(c) var(s) (independent factors).
    out.response_sd.push_back((scale * scale * shape_var.array() + scale_var * shape.array().square() +
                               scale_var * shape_var.array())
                                  .sqrt()
                                  .matrix());
    out.response.push_back(scale * shape);
  }
  return out;
}

}  // namespace pectus::planner
