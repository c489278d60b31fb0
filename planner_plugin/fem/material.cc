#include "planner_plugin/fem/material.h"

#include <cmath>

namespace pectus::planner {

bool IsotropicMaterial::IsValid(std::string* why) const {
  auto fail = [&](const std::string& reason) {
    if (why != nullptr) *why = "material '" + name + "': " + reason;
    return false;
  };
  if (!std::isfinite(youngs_modulus_mpa) || youngs_modulus_mpa <= 0.0) {
    return fail("Young's modulus must be finite and > 0 MPa, got " + std::to_string(youngs_modulus_mpa));
  }
  if (!std::isfinite(poisson_ratio) || poisson_ratio <= -1.0 || poisson_ratio >= 0.5) {
    return fail("Poisson's ratio must lie in (-1, 0.5), got " + std::to_string(poisson_ratio));
  }
  return true;
}

ElasticityMatrix IsotropicMaterial::Elasticity() const {
  const double E = youngs_modulus_mpa, nu = poisson_ratio;
  const double lambda = E * nu / ((1.0 + nu) * (1.0 - 2.0 * nu));
  const double mu = E / (2.0 * (1.0 + nu));
  ElasticityMatrix D = ElasticityMatrix::Zero();
  D.topLeftCorner<3, 3>().setConstant(lambda);
  D.topLeftCorner<3, 3>().diagonal().array() += 2.0 * mu;
  D.bottomRightCorner<3, 3>().diagonal().setConstant(mu);
  return D;
}

}  // namespace pectus::planner
