// pectus planner: Gaussian-process regression of one scalar output on a few inputs (Rasmussen & Williams,
// "Gaussian Processes for Machine Learning", 2006, ch. 2 and 5), for the response emulator (issue 14).
// An ARD kernel (one length scale per input: squared exponential, or Matern 5/2) plus a white-noise
// term, and a mean that is constant or linear in the inputs with a vague prior on its coefficients (R&W
// §2.7: the coefficients by generalised least squares, their uncertainty added to the predicted variance).
// The hyper-parameters maximise the log marginal likelihood (R&W eq. 2.30, the mean's coefficients at
// their optimum) with its analytic gradient (R&W eq. 5.9), by BFGS from a few starting points. Inputs and
// output are standardised inside (mean 0, standard deviation 1; a constant input is left out).
#pragma once

#include <Eigen/Core>
#include <string>

namespace pectus::planner {

/// The kernel's correlation as a function of the scaled distance r = |(x - x') / length scales|.
enum class GpKernel {
  kSquaredExponential,  ///< exp(-r^2 / 2)
  kMatern52,            ///< (1 + sqrt5 r + 5 r^2 / 3) exp(-sqrt5 r): twice differentiable
};

/// How the process is fitted.
struct GaussianProcessOptions {
  GpKernel kernel = GpKernel::kMatern52;  ///< default Matern 5/2
  /// The mean: a constant (false) or linear in the inputs (true, default): a linear trend extrapolates
  /// better to a new input outside the training inputs' hull (most new points in 5 or more dimensions).
  bool linear_mean = true;
  /// Length scales are kept within [min, max] (in standard deviations of their input) by a penalty on
  /// the likelihood. Defaults 0.05 and 100 (100: the input hardly matters).
  double min_length_scale = 0.05, max_length_scale = 100.0;
  /// The noise variance is kept within [min, max] times the output's variance. Defaults 1e-8 and 1.
  double min_noise_fraction = 1e-8, max_noise_fraction = 1.0;
  int starts = 3;            ///< BFGS runs from different starting points, the best kept. Default 3, >= 1
  int max_iterations = 200;  ///< per run, >= 1. Default 200
  /// A run stops when the gradient's largest component (per hyper-parameter, log scale) falls below
  /// this. Default 1e-5.
  double gradient_tolerance = 1e-5;
  /// False, with the reason, for a value out of range.
  bool IsValid(std::string* why) const;
};

/// What the fit found.
struct GaussianProcessSummary {
  bool converged = false;                ///< the best run met the gradient tolerance
  int iterations = 0;                    ///< of all runs
  double log_marginal_likelihood = 0.0;  ///< of the standardised outputs, at the optimum
  Eigen::VectorXd length_scales;         ///< per input, in its standard deviations (huge for a constant one)
  double signal_sd = 0.0;                ///< the kernel's standard deviation, output units
  double noise_sd = 0.0;                 ///< the white noise's standard deviation, output units
  std::string message;                   ///< one line
};

/// A Gaussian process fitted to n (input, output) pairs.
class GaussianProcess {
 public:
  /// Fits `y` (n) on `x` (n by p). Throws Error(kUsage) for invalid options, fewer than 3 points (or, for
  /// a linear mean, fewer than p + 3), mismatched shapes or non-finite values, and Error(kFailure) if no
  /// kernel matrix can be factorised.
  GaussianProcess(const Eigen::MatrixXd& x, const Eigen::VectorXd& y,
                  const GaussianProcessOptions& options = {});

  /// The predicted mean at `x` (p), and (optional) the standard deviation of the latent function there
  /// (`latent_sd`) and of a new observation (`observation_sd`: the latent's variance plus the noise's).
  double Predict(const Eigen::VectorXd& x, double* latent_sd = nullptr,
                 double* observation_sd = nullptr) const;

  const GaussianProcessSummary& summary() const { return summary_; }
  Eigen::Index num_inputs() const { return x_mean_.size(); }

 private:
  // Kernel between standardised points a and b (used inputs only) for log length scales `log_l`.
  double Correlation(const Eigen::VectorXd& a, const Eigen::VectorXd& b, const Eigen::VectorXd& log_l) const;
  GaussianProcessOptions options_;
  Eigen::VectorXd x_mean_, x_scale_;  // per input; scale 0 for a constant input (left out)
  double y_mean_ = 0.0, y_scale_ = 1.0;
  Eigen::MatrixXd xs_;                          // n by p standardised inputs
  Eigen::MatrixXd h_;                           // n by #mean terms
  Eigen::VectorXd log_l_;                       // per input
  double signal_var_ = 1.0, noise_var_ = 1e-4;  // standardised output units
  Eigen::VectorXd alpha_;                       // K^-1 (y - H beta)
  Eigen::VectorXd beta_;                        // the mean's coefficients
  Eigen::MatrixXd k_inverse_;                   // K^-1 (n by n)
  Eigen::MatrixXd hkh_inverse_;                 // (H' K^-1 H)^-1
  Eigen::MatrixXd kinv_h_;                      // K^-1 H
  GaussianProcessSummary summary_;
};

}  // namespace pectus::planner
