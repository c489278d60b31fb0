// pectus planner: the learned emulator of issue 14: a patient's response to the Nuss bar predicted from
// the patient's measurements alone, without a finite element run. The FE model is linear, so per bar
// position s the response is the force times a per-newton response g(s); the emulator learns g(s) from
// patients that were solved. Per position: a Gaussian process (gaussian_process.h) for log(sternal lift
// per newton); the per-newton response divided by that lift (its shape) by principal components
// (centered; the fewest components that explain a stated fraction of the training shapes' variance) and
// one Gaussian process per retained component's score. The predicted variance of each output coordinate
// is the processes' variances carried through the modes, plus the part the modes cannot represent, as the
// training patients show it when each is left out of the components (the leave-one-out projection
// residual), plus the scale's variance carried through the shape.
#pragma once

#include <Eigen/Core>
#include <memory>
#include <string>
#include <vector>

#include "planner_plugin/surrogate/gaussian_process.h"

namespace pectus::planner {

/// What each position's response is divided by before its principal components are taken (its scale is
/// then learnt by its own process, in log).
enum class ResponseScale {
  kNone,  ///< the per-newton response itself
  kLift,  ///< the sternal lift per newton (default: the issue's suggestion)
  kNorm,  ///< the response's Euclidean norm over all its coordinates
};

/// How the emulator is fitted.
struct ResponseEmulatorOptions {
  /// Every process's kernel, mean and optimiser (GaussianProcessOptions' defaults: Matern 5/2, linear mean).
  GaussianProcessOptions gp;
  /// Principal components kept per position: the fewest whose variance reaches this fraction of the
  /// training shapes' total, at most max_components and n - 2. In (0, 1]. Default 0.9999.
  double explained_fraction = 0.9999;
  /// Upper bound on the components per position (>= 1). Default 20.
  int max_components = 20;
  /// The scale divided out before the components (ResponseScale). Default kLift: over the 62 patients
  /// left out one at a time (docs/benchmarks/emulator.md) the lift gives the smaller worst case (4.1 %
  /// relative L2 against 6.0 % for the norm), the norm the smaller mean (0.29 % against 0.35 %).
  ResponseScale scale = ResponseScale::kLift;
  /// The fewest training patients accepted (>= 4). Default 5.
  int min_patients = 5;
  /// False, with the reason, for a value out of range.
  bool IsValid(std::string* why) const;
};

/// The prediction for one patient: per bar position, per newton of bar force.
struct ResponseEmulatorPrediction {
  Eigen::VectorXd lift_per_newton;           ///< q sternal lifts per newton (median of the log-normal), mm/N
  Eigen::VectorXd lift_sd;                   ///< q standard deviations of the lift, mm/N
  std::vector<Eigen::VectorXd> response;     ///< per position, m output coordinates, mm/N
  std::vector<Eigen::VectorXd> response_sd;  ///< per position, m standard deviations, mm/N
};

/// What the fit kept, per position.
struct ResponseEmulatorSummary {
  std::vector<int> components;       ///< per position: principal components kept
  std::vector<double> explained;     ///< per position: their fraction of the shapes' variance
  std::vector<double> residual_rms;  ///< per position: RMS of the leave-one-out projection residual
  std::vector<GaussianProcessSummary> lift_gp;   ///< per position: the log-lift process
  std::vector<GaussianProcessSummary> scale_gp;  ///< per position: the log-norm process (kNorm only)
  double fit_seconds = 0.0;
  std::string message;  ///< one line
};

/// The emulator, fitted to n patients.
class ResponseEmulator {
 public:
  /// Fits the emulator. `inputs`: n by p patient parameters (any units: standardised inside);
  /// `lift_per_newton`: n by q sternal lifts per newton (mm/N, > 0); `responses`: q matrices, n by m
  /// per-newton responses (mm/N; a row is one patient's output coordinates, the same m at every position).
  /// Throws Error(kUsage) for invalid options, fewer than options.min_patients patients, shapes that
  /// disagree, non-finite values or a lift that is not positive.
  ResponseEmulator(const Eigen::MatrixXd& inputs, const Eigen::MatrixXd& lift_per_newton,
                   const std::vector<Eigen::MatrixXd>& responses,
                   const ResponseEmulatorOptions& options = {});
  ~ResponseEmulator();
  ResponseEmulator(ResponseEmulator&&) noexcept;

  /// The prediction for a patient with parameters `x` (p). Throws Error(kUsage) for another p.
  ResponseEmulatorPrediction Predict(const Eigen::VectorXd& x) const;

  const ResponseEmulatorSummary& summary() const { return summary_; }
  Eigen::Index num_inputs() const { return num_inputs_; }
  Eigen::Index num_positions() const { return static_cast<Eigen::Index>(positions_.size()); }
  Eigen::Index num_outputs() const { return num_outputs_; }

 private:
  struct Position;  // one position's processes and modes
  std::vector<std::unique_ptr<Position>> positions_;
  ResponseEmulatorOptions options_;
  Eigen::Index num_inputs_ = 0, num_outputs_ = 0;
  ResponseEmulatorSummary summary_;
};

}  // namespace pectus::planner
