// pectus: one local polyharmonic RBF, s(x) = p(x) + sum_j alpha_j |x - y_j|^3, fitted by penalised least
// squares: the building block of the partition-of-unity implicit surface (shape/rbf_implicit.h).
#pragma once

#include <Eigen/Core>

#include "shape/core/geometry.h"

namespace pectus {

/// What one local fit is asked to match. Centres and constraint points are in mm; the fit works in a
/// local frame (x - origin) / scale so that its conditioning and the meaning of `smoothing` do not
/// depend on the size of the patch.
struct LocalRbfProblem {
  Points3 centres;          ///< #centres by 3 (mm): where the kernels sit (the y_j)
  Points3 points;           ///< #constraints by 3 (mm): where values are asked for (the x_k)
  Eigen::VectorXd values;   ///< #constraints (mm): the asked values f_k (0 on the surface, +-eps off it)
  Eigen::VectorXd weights;  ///< #constraints, >= 0: weight of each constraint
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();  ///< centre of the local frame (mm)
  double scale = 1.0;                                ///< radius of the local frame (mm), > 0
  /// Polynomial part of degree 2 (10 terms) instead of 1 (4 terms): a sphere or any quadric is then
  /// reproduced exactly, so a hole in a curved surface is filled with its curvature (as the local
  /// quadrics of Ohtake et al. 2003). Falls back to degree 1 when the constraints cannot fix a quadric.
  bool quadratic = true;
};

/// A fitted local spline (dissertation Eq. 9 with phi(r) = r^3 and a polynomial p of degree 2 or 1).
///
/// Fit minimises, in the local frame (x' = (x - origin) / scale, f' = f / scale),
///   sum_k w_k (s'(x'_k) - f'_k)^2 / sum_k w_k  +  smoothing * alpha^T Phi alpha,
/// subject to the side conditions sum_j alpha_j q(y'_j) = 0 for every monomial q of p (the second block
/// row of dissertation Eq. 10), where Phi_ij = |y'_i - y'_j|^3. alpha^T Phi alpha is the spline's bending
/// energy (r^3 is conditionally positive definite of order 2 in 3D), so `smoothing` is the smoothing
/// parameter of Carr et al. (2001), Sec. 3.2, for centres fewer than constraints. The side conditions
/// are imposed through a basis of their null space, which also handles coplanar centres.
class LocalRbf {
 public:
  LocalRbf() = default;

  /// Fits the spline. False (and `*this` unchanged) if the constraints cannot fix even a linear
  /// function (fewer than 4 of them with weight, or all coplanar) or the system is not finite.
  /// @param[in] problem    centres, constraints and the local frame
  /// @param[in] smoothing  weight of the bending energy (dimensionless), >= 0
  bool Fit(const LocalRbfProblem& problem, double smoothing);

  /// s(x) in mm at a point x (mm).
  double Evaluate(const Eigen::Vector3d& x) const;

  /// Number of kernels.
  Eigen::Index num_centres() const { return centres_.rows(); }

 private:
  Eigen::Matrix<double, Eigen::Dynamic, 3> centres_;  // #centres by 3, local frame, one column per axis
  Eigen::VectorXd alpha_;                             // #centres
  Eigen::Matrix<double, 10, 1> beta_ = Eigen::Matrix<double, 10, 1>::Zero();  // p(x') coefficients
  int terms_ = 4;                                                             // 4 or 10 monomials
  Eigen::Vector3d origin_ = Eigen::Vector3d::Zero();
  double scale_ = 1.0;
};

}  // namespace pectus
