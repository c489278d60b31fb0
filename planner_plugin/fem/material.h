// pectus planner: linear isotropic elastic materials (dissertation §4.1.2, Table 1; the cartilage default
// calibrated to in vivo forces).
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

/// Costal cartilage's Young's modulus in the dissertation's Table 1, MPa.
inline constexpr double kDissertationCartilageModulusMpa = 20.0;
/// The default costal cartilage modulus, MPa: an effective modulus calibrated so that the model needs the
/// force measured in vivo to lift a sternum by its depression (about 175 N in adolescents, Weber et al.,
/// J Thorac Cardiovasc Surg 2006). The model has only bone and cartilage, so this modulus also stands for
/// what it lacks (intercostal muscles, diaphragm slips, transversus thoracis, pleura, skin). Evidence and
/// figures: docs/planner.md, "Force to lift the sternum".
inline constexpr double kCalibratedCartilageModulusMpa = 80.0;

/// The three materials of the ribcage: sternum and ribs as in the dissertation's Table 1; the costal
/// cartilage, which varies most between patients (and with age), calibrated to in vivo forces
/// (kCalibratedCartilageModulusMpa; kDissertationCartilageModulusMpa gives Table 1).
struct RibcageMaterials {
  IsotropicMaterial sternum{"sternum", 11500.0, 0.3};
  IsotropicMaterial rib{"rib", 5000.0, 0.3};
  IsotropicMaterial cartilage{"costal_cartilage", kCalibratedCartilageModulusMpa, 0.4};
};

}  // namespace pectus::planner
