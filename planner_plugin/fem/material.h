// pectus planner: linear isotropic elastic materials (dissertation §4.1.2, Table 1).
#pragma once

#include <Eigen/Core>
#include <string>

namespace pectus::planner {

/// 6 by 6 elasticity matrix in Voigt order (xx, yy, zz, xy, yz, zx), engineering shear strains, MPa.
using ElasticityMatrix = Eigen::Matrix<double, 6, 6>;

/// A linear, isotropic, elastic material. Units: MPa = N/mm², consistent with mm and N everywhere.
struct IsotropicMaterial {
  std::string name;                 ///< e.g. "sternum"; names the material in messages and exports
  double youngs_modulus_mpa = 0.0;  ///< E > 0, MPa
  double poisson_ratio = 0.0;       ///< -1 < nu < 0.5

  /// False, with the reason in `why`, unless E is finite and > 0 and -1 < nu < 0.5.
  bool IsValid(std::string* why) const;
  /// Shear modulus G = E / (2 (1 + nu)), MPa.
  double ShearModulus() const { return youngs_modulus_mpa / (2.0 * (1.0 + poisson_ratio)); }
  /// The elasticity matrix D with sigma = D epsilon (Voigt order above, engineering shear strains).
  ElasticityMatrix Elasticity() const;
};

/// The three materials of the ribcage (dissertation Table 1). Cartilage varies most between patients
/// (and with age), so it is the one a caller usually overrides.
struct RibcageMaterials {
  IsotropicMaterial sternum{"sternum", 11500.0, 0.3};
  IsotropicMaterial rib{"rib", 5000.0, 0.3};
  IsotropicMaterial cartilage{"costal_cartilage", 20.0, 0.4};
};

}  // namespace pectus::planner
