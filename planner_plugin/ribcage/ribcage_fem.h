// pectus planner: the finite element model of a patient's ribcage (dissertation §4.1.2): three materials,
// the posterior rib ends clamped, and the Nuss bar's push as a force spread over a contact patch under
// the sternum. The stiffness is factorised once; every bar position and force is then a cheap solve.
#pragma once

#include <Eigen/Core>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "planner_plugin/fem/linear_elastic_solver.h"
#include "planner_plugin/fem/material.h"
#include "planner_plugin/ribcage/patient_ribcage.h"

namespace pectus::planner {

/// Where the bar pushes the sternum, and how hard.
struct BarLoad {
  /// Along the sternum from the notch (axial distance, as the sternal length is measured): a fraction
  /// of the sternal length, or millimetres when `position_in_mm`.
  double position = 0.85;
  bool position_in_mm = false;
  double force_n = 100.0;  ///< magnitude of the push, N (> 0)
  /// e.g. "0.85 L, 1700 N" or "140 mm, 1700 N".
  std::string Name() const;
};

/// The dissertation's load cases: 3 bar positions x 8 forces (50, 70, 100, 200, 400, 800, 1500,
/// 2000 N) = 24 per patient. The dissertation shows its three positions only in a figure (Figure 27,
/// along the lower sternum); pectus takes 0.65, 0.75 and 0.85 of the sternal length from the notch.
std::vector<BarLoad> DissertationLoadCases();

/// Options of the ribcage's finite element model.
struct RibcageFemOptions {
  /// Materials per region (sternum, rib, costal cartilage); Table 1 of the dissertation by default.
  RibcageMaterials materials;
  /// Cranio-caudal width of the bar's contact under the sternum, mm (the bar's width). The push is spread
  /// over the sternum's back with a raised-cosine profile of this full width at half maximum (twice
  /// this in all), so the load moves continuously with the bar. Default 12.
  double contact_width_mm = 12.0;
  /// Direction of the bar's push (normalised): anterior, -y in LPS, by default.
  Eigen::Vector3d push_direction = -Eigen::Vector3d::UnitY();
  SparseCholeskyOptions solver;
  bool IsValid(std::string* why) const;
};

/// One solved load case.
struct BarResult {
  BarLoad load;
  Points3 displacement;        ///< #nodes by 3, mm
  double sternum_lift_mm = 0;  ///< anterior displacement of the sternum at the level of deepest depression
  double max_displacement_mm = 0;
  Eigen::Index contact_faces = 0;
  double contact_area_mm2 = 0;  ///< integral of the contact profile over the sternum's back (effective area)
};

/// The force a bar position needs to lift the sternum by the patient's depression (the model is
/// linear, so it is depression / lift per newton).
struct ForceToLift {
  BarLoad position;               ///< force_n unused
  double lift_per_newton_mm = 0;  ///< sternal lift under 1 N at that position, mm/N
  double force_n = 0;             ///< depression / lift_per_newton_mm
};

/// RibcageFem::SternumLiftTies from the ribcage alone (its measurement slice and anterior midline; no
/// finite element model needed). Throws Error(kFailure) if the slice misses the sternum.
std::vector<std::pair<std::int32_t, double>> SternumLiftTiesOf(const PatientRibcage& ribcage);

/// A patient's ribcage as a finite element model: assembled and factorised on construction.
class RibcageFem {
 public:
  /// Throws Error(kUsage) for invalid options, Error(kFailure) if the factorisation fails.
  RibcageFem(const PatientRibcage& ribcage, const RibcageFemOptions& options = {});

  /// Solves the load cases on the single factorisation: one right-hand side per distinct bar position
  /// (unit force), every case at that position being its force times that solution (the model is
  /// linear). Throws Error(kUsage) naming the load if it lies off the sternum or its force is not
  /// positive.
  std::vector<BarResult> Solve(const std::vector<BarLoad>& loads) const;

  /// Height (z, mm) at which a bar at `load.position` meets the sternum.
  double BarLevelZ(const BarLoad& load) const;
  /// The sternum's posterior faces the contact profile reaches (within one contact width of the bar
  /// level; at least the row of faces nearest to it).
  Tri6Connectivity ContactPatch(const BarLoad& load) const;
  /// The contact profile at height z: 1 at the bar level, falling as a raised cosine to 0 one contact
  /// width away.
  double ContactProfile(const BarLoad& load, double z) const;
  /// Nodal forces of a load, 3 #nodes, N.
  Eigen::VectorXd NodalForces(const BarLoad& load) const;
  /// Anterior displacement of the sternum's anterior midline at the measurement slice (the level of
  /// deepest depression), interpolated between midline nodes, mm.
  double SternumLift(const Points3& displacement) const;
  /// SternumLift as a linear functional: (node, weight) pairs on the nodes' y displacement (lift = sum of
  /// weight u_y(node)).
  std::vector<std::pair<std::int32_t, double>> SternumLiftTies() const;
  /// ForceToLift for each position (fractions of the sternal length, or mm).
  std::vector<ForceToLift> ForceToLiftSternum(const std::vector<BarLoad>& positions) const;

  const PatientRibcage& ribcage() const { return ribcage_; }
  const LinearElasticSolver& solver() const { return *solver_; }
  const RibcageFemOptions& options() const { return options_; }

 private:
  const PatientRibcage& ribcage_;
  RibcageFemOptions options_;
  std::unique_ptr<LinearElasticSolver> solver_;
  double notch_z_ = 0, sternal_length_ = 0;
};

}  // namespace pectus::planner
