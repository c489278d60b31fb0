// pectus: robust losses for iteratively reweighted least squares, with a scale from the median absolute
// deviation.
#pragma once

#include <string>
#include <vector>

namespace pectus {

/// M-estimator of a residual r with scale c (Zhang 1997, "Parameter estimation techniques", Table 1).
enum class RobustLoss {
  kNone,    ///< least squares: w = 1
  kHuber,   ///< w = 1 for |r| <= c, c / |r| beyond; c = 1.345 sigma
  kCauchy,  ///< w = 1 / (1 + (r/c)^2); c = 2.3849 sigma
  kTukey,   ///< w = (1 - (r/c)^2)^2 for |r| <= c, 0 beyond; c = 4.6851 sigma
};

/// Parses "none", "huber", "cauchy", "tukey"; throws Error(kUsage) otherwise.
RobustLoss ParseRobustLoss(const std::string& name);
std::string ToString(RobustLoss loss);

/// The tuning constant c / sigma giving 95 % efficiency on Gaussian residuals (1 for kNone).
double RobustTuningConstant(RobustLoss loss);

/// The IRLS weight w(r) = rho'(r) / r of `loss` at residual r for the scale c (same unit as r, > 0).
double RobustWeight(RobustLoss loss, double r, double c);

/// A robust standard deviation of residuals: 1.4826 times the median of |r| (the median absolute
/// deviation about zero; residuals of a fit are centred on zero). Reorders `abs_residuals`. 0 if empty.
/// @param[in,out] abs_residuals  |r| values
double MadScale(std::vector<double>* abs_residuals);

}  // namespace pectus
