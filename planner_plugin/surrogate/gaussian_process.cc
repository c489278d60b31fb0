#include "planner_plugin/surrogate/gaussian_process.h"

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>
#include <vector>

#include "shape/core/error.h"

namespace pectus::planner {

bool GaussianProcessOptions::IsValid(std::string* why) const {
  auto fail = [&](const char* text) {
    if (why) *why = text;
    return false;
  };
  if (!(min_length_scale > 0.0 && max_length_scale > min_length_scale && std::isfinite(max_length_scale)))
    return fail("Gaussian process: length-scale bounds must satisfy 0 < min < max < inf");
  if (!(min_noise_fraction > 0.0 && max_noise_fraction >= min_noise_fraction &&
        std::isfinite(max_noise_fraction)))
    return fail("Gaussian process: noise bounds must satisfy 0 < min <= max < inf");
  if (starts < 1) return fail("Gaussian process: starts must be >= 1");
  if (max_iterations < 1) return fail("Gaussian process: max_iterations must be >= 1");
  if (!(gradient_tolerance > 0.0)) return fail("Gaussian process: gradient_tolerance must be > 0");
  return true;
}

namespace {

constexpr double kSqrt5 = 2.2360679774997896964;
// The penalty keeping a log hyper-parameter within its bounds (per unit of squared excess).
constexpr double kPenalty = 10.0;
// Bounds on the log signal variance (standardised outputs).
constexpr double kLogSignalMin = -9.2, kLogSignalMax = 4.6;

// Correlation c(r^2) and the factor g with dc/dlog l_d = g * (delta_d / l_d)^2.
inline void Kernel(GpKernel kernel, double r2, double* c, double* g) {
  if (kernel == GpKernel::kSquaredExponential) {
    *c = std::exp(-0.5 * r2);
    *g = *c;
  } else {
    const double r = std::sqrt(r2), e = std::exp(-kSqrt5 * r);
    *c = (1.0 + kSqrt5 * r + 5.0 * r2 / 3.0) * e;
    *g = 5.0 / 3.0 * (1.0 + kSqrt5 * r) * e;
  }
}

// The negative log marginal likelihood and its gradient for standardised data (Rasmussen & Williams eq.
// 2.30 and 5.9), with the mean's coefficients by generalised least squares.
class Objective {
 public:
  Objective(const Eigen::MatrixXd& x, const Eigen::VectorXd& y, const Eigen::MatrixXd& h,
            const GaussianProcessOptions& options)
      : y_(y), h_(h), options_(options), n_(x.rows()), p_(x.cols()) {
    d2_.resize(static_cast<std::size_t>(p_));
    for (Eigen::Index d = 0; d < p_; ++d) {
      Eigen::MatrixXd& m = d2_[static_cast<std::size_t>(d)];
      m.resize(n_, n_);
      for (Eigen::Index j = 0; j < n_; ++j)
        for (Eigen::Index i = 0; i < n_; ++i) m(i, j) = (x(i, d) - x(j, d)) * (x(i, d) - x(j, d));
    }
    lo_.resize(p_ + 2);
    hi_.resize(p_ + 2);
    lo_.head(p_).setConstant(std::log(options.min_length_scale));
    hi_.head(p_).setConstant(std::log(options.max_length_scale));
    lo_(p_) = kLogSignalMin;
    hi_(p_) = kLogSignalMax;
    lo_(p_ + 1) = std::log(options.min_noise_fraction);
    hi_(p_ + 1) = std::log(options.max_noise_fraction);
  }

  // theta = [log l (p), log signal variance, log noise variance]. Infinity if K cannot be factorised.
  double operator()(const Eigen::VectorXd& theta, Eigen::VectorXd* gradient) const {
    const double sf2 = std::exp(theta(p_)), sn2 = std::exp(theta(p_ + 1));
    Eigen::VectorXd inv_l2(p_);
    for (Eigen::Index d = 0; d < p_; ++d) inv_l2(d) = std::exp(-2.0 * theta(d));
    Eigen::MatrixXd k(n_, n_), g(n_, n_);
    for (Eigen::Index j = 0; j < n_; ++j) {
      for (Eigen::Index i = j; i < n_; ++i) {
        double r2 = 0.0;
        for (Eigen::Index d = 0; d < p_; ++d) r2 += d2_[static_cast<std::size_t>(d)](i, j) * inv_l2(d);
        double c, gg;
        Kernel(options_.kernel, r2, &c, &gg);
        k(i, j) = k(j, i) = sf2 * c;
        g(i, j) = g(j, i) = sf2 * gg;
      }
      k(j, j) += sn2;
    }
    const Eigen::LLT<Eigen::MatrixXd> llt(k);
    if (llt.info() != Eigen::Success) return std::numeric_limits<double>::infinity();
    const Eigen::MatrixXd kinv_h = llt.solve(h_);
    const Eigen::VectorXd beta = (h_.transpose() * kinv_h).ldlt().solve(kinv_h.transpose() * y_);
    const Eigen::VectorXd r = y_ - h_ * beta;
    const Eigen::VectorXd alpha = llt.solve(r);
    const Eigen::MatrixXd& l = llt.matrixLLT();
    double value = 0.5 * r.dot(alpha) + l.diagonal().array().log().sum() +
                   0.5 * static_cast<double>(n_) * std::log(2.0 * std::numbers::pi);
    if (gradient != nullptr) {
      // W = K^-1 - alpha alpha'; dNLL/dtheta_j = tr(W dK/dtheta_j) / 2.
      Eigen::MatrixXd w = llt.solve(Eigen::MatrixXd::Identity(n_, n_));
      w.noalias() -= alpha * alpha.transpose();
      gradient->resize(p_ + 2);
      for (Eigen::Index d = 0; d < p_; ++d)
        (*gradient)(d) =
            0.5 * (w.array() * g.array() * d2_[static_cast<std::size_t>(d)].array()).sum() * inv_l2(d);
      Eigen::MatrixXd kf = k;
      kf.diagonal().array() -= sn2;
      (*gradient)(p_) = 0.5 * (w.array() * kf.array()).sum();
      (*gradient)(p_ + 1) = 0.5 * sn2 * w.trace();
    }
    // Keep the hyper-parameters within their bounds.
    for (Eigen::Index j = 0; j < p_ + 2; ++j) {
      const double over = std::max(0.0, theta(j) - hi_(j)), under = std::max(0.0, lo_(j) - theta(j));
      value += kPenalty * (over * over + under * under);
      if (gradient != nullptr) (*gradient)(j) += 2.0 * kPenalty * (over - under);
    }
    return value;
  }

 private:
  const Eigen::VectorXd& y_;
  const Eigen::MatrixXd& h_;
  const GaussianProcessOptions& options_;
  Eigen::Index n_, p_;
  std::vector<Eigen::MatrixXd> d2_;  // per input: squared differences
  Eigen::VectorXd lo_, hi_;
};

struct Minimum {
  Eigen::VectorXd theta;
  double value = std::numeric_limits<double>::infinity();
  int iterations = 0;
  bool converged = false;
};

// BFGS with a backtracking (Armijo) line search; steps limited to 2 in log scale.
Minimum Bfgs(const Objective& f, Eigen::VectorXd theta, const GaussianProcessOptions& options) {
  Minimum out;
  Eigen::VectorXd g;
  double value = f(theta, &g);
  if (!std::isfinite(value)) return out;
  const Eigen::Index m = theta.size();
  Eigen::MatrixXd inverse_hessian = Eigen::MatrixXd::Identity(m, m);
  int it = 0;
  for (; it < options.max_iterations; ++it) {
    if (g.cwiseAbs().maxCoeff() < options.gradient_tolerance) {
      out.converged = true;
      break;
    }
    Eigen::VectorXd direction = -inverse_hessian * g;
    if (direction.dot(g) >= 0.0) {  // not a descent direction: restart from steepest descent
      inverse_hessian.setIdentity();
      direction = -g;
    }
    const double longest = direction.cwiseAbs().maxCoeff();
    if (longest > 2.0) direction *= 2.0 / longest;
    double step = 1.0, next_value = value;
    Eigen::VectorXd next, next_g;
    bool accepted = false;
    for (int halving = 0; halving < 40; ++halving, step *= 0.5) {
      next = theta + step * direction;
      next_value = f(next, &next_g);
      if (std::isfinite(next_value) && next_value <= value + 1e-4 * step * direction.dot(g)) {
        accepted = true;
        break;
      }
    }
    if (!accepted) {
      out.converged = g.cwiseAbs().maxCoeff() < 1e3 * options.gradient_tolerance;
      break;
    }
    const Eigen::VectorXd s = next - theta, dy = next_g - g;
    const double sy = s.dot(dy);
    if (sy > 1e-12) {
      if (it == 0) inverse_hessian *= sy / dy.squaredNorm();
      const double rho = 1.0 / sy;
      const Eigen::MatrixXd a = Eigen::MatrixXd::Identity(m, m) - rho * s * dy.transpose();
      inverse_hessian = a * inverse_hessian * a.transpose() + rho * s * s.transpose();
    }
    const double change = value - next_value;
    theta = next;
    g = next_g;
    value = next_value;
    if (change >= 0.0 && change < 1e-12 * (1.0 + std::abs(value))) {
      out.converged = true;
      ++it;
      break;
    }
  }
  out.theta = theta;
  out.value = value;
  out.iterations = it;
  return out;
}

}  // namespace

GaussianProcess::GaussianProcess(const Eigen::MatrixXd& x, const Eigen::VectorXd& y,
                                 const GaussianProcessOptions& options)
    : options_(options) {
  std::string why;
  if (!options.IsValid(&why)) ThrowUsage(why);
  const Eigen::Index n = x.rows(), p = x.cols();
  if (y.size() != n)
    ThrowUsage("Gaussian process: " + std::to_string(n) + " input rows but " + std::to_string(y.size()) +
               " outputs");
  if (!x.allFinite() || !y.allFinite()) ThrowUsage("Gaussian process: an input or output is not finite");
  // Standardise; a constant input is left out.
  x_mean_ = x.colwise().mean().transpose();
  x_scale_.resize(p);
  std::vector<Eigen::Index> used;
  for (Eigen::Index d = 0; d < p; ++d) {
    const double sd =
        n > 1 ? std::sqrt((x.col(d).array() - x_mean_(d)).square().sum() / static_cast<double>(n - 1)) : 0.0;
    x_scale_(d) = sd > 1e-12 * (1.0 + std::abs(x_mean_(d))) ? sd : 0.0;
    if (x_scale_(d) > 0.0) used.push_back(d);
  }
  const auto pu = static_cast<Eigen::Index>(used.size());
  const Eigen::Index terms = options.linear_mean ? pu + 1 : 1;
  if (n < terms + 2)
    ThrowUsage("Gaussian process: " + std::to_string(n) + " points are too few for " + std::to_string(terms) +
               " mean terms (at least " + std::to_string(terms + 2) + " needed)");
  xs_.resize(n, pu);
  for (Eigen::Index j = 0; j < pu; ++j)
    xs_.col(j) =
        (x.col(used[static_cast<std::size_t>(j)]).array() - x_mean_(used[static_cast<std::size_t>(j)])) /
        x_scale_(used[static_cast<std::size_t>(j)]);
  y_mean_ = y.mean();
  const double y_sd = std::sqrt((y.array() - y_mean_).square().sum() / static_cast<double>(n - 1));
  y_scale_ = y_sd > 1e-300 ? y_sd : 1.0;
  const Eigen::VectorXd ys = (y.array() - y_mean_) / y_scale_;
  h_.resize(n, terms);
  h_.col(0).setOnes();
  if (options.linear_mean) h_.rightCols(pu) = xs_;

  // Maximise the likelihood from a few starting points.
  const Objective objective(xs_, ys, h_, options_);
  const double typical = std::sqrt(std::max<double>(1.0, static_cast<double>(pu)));
  const double start_l[] = {1.0, 3.0, 0.4, 8.0}, start_noise[] = {1e-2, 1e-4, 1e-1, 1e-3};
  Minimum best;
  int iterations = 0;
  for (int s = 0; s < options.starts; ++s) {
    Eigen::VectorXd theta(pu + 2);
    theta.head(pu).setConstant(std::log(typical * start_l[s % 4] * (1.0 + s / 4)));
    theta(pu) = 0.0;
    theta(pu + 1) =
        std::log(std::clamp(start_noise[s % 4], options.min_noise_fraction, options.max_noise_fraction));
    const Minimum m = Bfgs(objective, theta, options_);
    iterations += m.iterations;
    if (m.value < best.value) best = m;
  }
  if (!std::isfinite(best.value)) ThrowFailure("Gaussian process: no kernel matrix could be factorised");

  // The fitted process.
  log_l_ = best.theta.head(pu);
  signal_var_ = std::exp(best.theta(pu));
  noise_var_ = std::exp(best.theta(pu + 1));
  Eigen::MatrixXd k(n, n);
  for (Eigen::Index j = 0; j < n; ++j)
    for (Eigen::Index i = 0; i < n; ++i) k(i, j) = signal_var_ * Correlation(xs_.row(i), xs_.row(j), log_l_);
  k.diagonal().array() += noise_var_;
  const Eigen::LLT<Eigen::MatrixXd> llt(k);
  if (llt.info() != Eigen::Success)
    ThrowFailure("Gaussian process: the fitted kernel matrix is not positive definite");
  k_inverse_ = llt.solve(Eigen::MatrixXd::Identity(n, n));
  kinv_h_ = k_inverse_ * h_;
  hkh_inverse_ = (h_.transpose() * kinv_h_).inverse();
  beta_ = hkh_inverse_ * (kinv_h_.transpose() * ys);
  alpha_ = k_inverse_ * (ys - h_ * beta_);

  summary_.converged = best.converged;
  summary_.iterations = iterations;
  summary_.log_marginal_likelihood = -best.value;
  summary_.length_scales = Eigen::VectorXd::Constant(p, std::numeric_limits<double>::infinity());
  for (Eigen::Index j = 0; j < pu; ++j)
    summary_.length_scales(used[static_cast<std::size_t>(j)]) = std::exp(log_l_(j));
  summary_.signal_sd = std::sqrt(signal_var_) * y_scale_;
  summary_.noise_sd = std::sqrt(noise_var_) * y_scale_;
  char text[200];
  std::snprintf(text, sizeof(text),
                "%s after %d iterations, log marginal likelihood %.4g, signal sd %.3g, noise sd %.3g",
                best.converged ? "converged" : "not converged", iterations, summary_.log_marginal_likelihood,
                summary_.signal_sd, summary_.noise_sd);
  summary_.message = text;
}

double GaussianProcess::Correlation(const Eigen::VectorXd& a, const Eigen::VectorXd& b,
                                    const Eigen::VectorXd& log_l) const {
  double r2 = 0.0;
  for (Eigen::Index d = 0; d < a.size(); ++d) {
    const double t = (a(d) - b(d)) * std::exp(-log_l(d));
    r2 += t * t;
  }
  double c, g;
  Kernel(options_.kernel, r2, &c, &g);
  return c;
}

double GaussianProcess::Predict(const Eigen::VectorXd& x, double* latent_sd, double* observation_sd) const {
  if (x.size() != x_mean_.size())
    ThrowUsage("Gaussian process: a point of " + std::to_string(x.size()) + " inputs, the process has " +
               std::to_string(x_mean_.size()));
  Eigen::VectorXd xs(xs_.cols());
  for (Eigen::Index d = 0, j = 0; d < x.size(); ++d)
    if (x_scale_(d) > 0.0) xs(j++) = (x(d) - x_mean_(d)) / x_scale_(d);
  const Eigen::Index n = xs_.rows();
  Eigen::VectorXd k(n);
  for (Eigen::Index i = 0; i < n; ++i) k(i) = signal_var_ * Correlation(xs, xs_.row(i), log_l_);
  Eigen::VectorXd h(h_.cols());
  h(0) = 1.0;
  if (options_.linear_mean) h.tail(xs.size()) = xs;
  const double mean = h.dot(beta_) + k.dot(alpha_);
  if (latent_sd != nullptr || observation_sd != nullptr) {
    // R&W eq. 2.42: the kernel's variance, less what the data explain, plus the mean's uncertainty.
    const Eigen::VectorXd r = h - kinv_h_.transpose() * k;
    const double var = std::max(0.0, signal_var_ - k.dot(k_inverse_ * k) + r.dot(hkh_inverse_ * r));
    if (latent_sd != nullptr) *latent_sd = std::sqrt(var) * y_scale_;
    if (observation_sd != nullptr) *observation_sd = std::sqrt(var + noise_var_) * y_scale_;
  }
  return y_mean_ + y_scale_ * mean;
}

}  // namespace pectus::planner
