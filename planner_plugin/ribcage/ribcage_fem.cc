#include "planner_plugin/ribcage/ribcage_fem.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>

#include "planner_plugin/fem/assembly.h"
#include "planner_plugin/fem/surface_load.h"
#include "shape/core/error.h"

namespace pectus::planner {

std::string BarLoad::Name() const {
  char text[96];
  if (position_in_mm) {
    std::snprintf(text, sizeof(text), "%g mm, %g N", position, force_n);
  } else {
    std::snprintf(text, sizeof(text), "%g L, %g N", position, force_n);
  }
  return text;
}

std::vector<BarLoad> DissertationLoadCases() {
  std::vector<BarLoad> loads;
  for (double position : {0.65, 0.75, 0.85}) {
    for (double force : {50.0, 70.0, 100.0, 200.0, 400.0, 800.0, 1500.0, 2000.0}) {
      loads.push_back({position, false, force});
    }
  }
  return loads;
}

bool RibcageFemOptions::IsValid(std::string* why) const {
  for (const IsotropicMaterial* m : {&materials.sternum, &materials.rib, &materials.cartilage}) {
    if (!m->IsValid(why)) return false;
  }
  if (!(contact_width_mm > 0 && contact_width_mm < 100)) {
    if (why) *why = "contact_width_mm must be in (0, 100)";
    return false;
  }
  if (!push_direction.allFinite() || push_direction.norm() < 1e-9) {
    if (why) *why = "push_direction must be a non-zero vector";
    return false;
  }
  return solver.IsValid(why);
}

RibcageFem::RibcageFem(const PatientRibcage& ribcage, const RibcageFemOptions& options)
    : ribcage_(ribcage), options_(options) {
  std::string why;
  if (!options.IsValid(&why)) ThrowUsage("ribcage finite element options: " + why);
  options_.push_direction.normalize();
  const std::vector<IsotropicMaterial> materials = {options.materials.sternum, options.materials.rib,
                                                    options.materials.cartilage};
  solver_ = std::make_unique<LinearElasticSolver>(ribcage.mesh, materials, AllDofsOf(ribcage.fixed_nodes),
                                                  options.solver);
  notch_z_ = ribcage.measured.notch_z_mm;
  sternal_length_ = ribcage.measured.sternal_length_mm;
}

double RibcageFem::BarLevelZ(const BarLoad& load) const {
  const double distance = load.position_in_mm ? load.position : load.position * sternal_length_;
  return notch_z_ - distance;
}

Tri6Connectivity RibcageFem::ContactPatch(const BarLoad& load) const {
  const double level = BarLevelZ(load);
  if (level > notch_z_ || level < notch_z_ - sternal_length_) {
    ThrowUsage("bar at " + load.Name() + ": the position lies off the sternum (0 to " +
               std::to_string(sternal_length_) + " mm, or 0 to 1 of the sternal length, from the notch)");
  }
  const Tri6Connectivity& faces = ribcage_.sternum_posterior_faces;
  const Points3& x = ribcage_.mesh.nodes;
  // Faces whose height range comes within one contact width of the level (the profile's support).
  std::vector<Eigen::Index> chosen;
  const double reach = options_.contact_width_mm;
  for (Eigen::Index f = 0; f < faces.rows(); ++f) {
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (int a = 0; a < 6; ++a) {
      lo = std::min(lo, x(faces(f, a), 2));
      hi = std::max(hi, x(faces(f, a), 2));
    }
    if (hi > level - reach && lo < level + reach) chosen.push_back(f);
  }
  if (chosen.empty()) ThrowFailure("bar at " + load.Name() + ": no sternal face near the bar level");
  Tri6Connectivity patch(static_cast<Eigen::Index>(chosen.size()), 6);
  for (std::size_t k = 0; k < chosen.size(); ++k)
    patch.row(static_cast<Eigen::Index>(k)) = faces.row(chosen[k]);
  return patch;
}

double RibcageFem::ContactProfile(const BarLoad& load, double z) const {
  const double s = std::abs(z - BarLevelZ(load)) / options_.contact_width_mm;
  return s < 1.0 ? 0.5 * (1.0 + std::cos(std::numbers::pi * s)) : 0.0;
}

Eigen::VectorXd RibcageFem::NodalForces(const BarLoad& load) const {
  if (!(load.force_n > 0) || !std::isfinite(load.force_n)) {
    ThrowUsage("bar at " + load.Name() + ": the force must be positive and finite");
  }
  const Tri6Connectivity patch = ContactPatch(load);
  auto phi = [&](const Eigen::Vector3d& x) { return ContactProfile(load, x.z()); };
  const double area = AddProfiledTraction(ribcage_.mesh.nodes, patch, Eigen::Vector3d::Zero(), phi, nullptr);
  if (!(area > 0)) ThrowFailure("bar at " + load.Name() + ": the contact profile has no area on the sternum");
  // A uniform traction F / area shaped by the profile: the nodal forces sum to F exactly.
  Eigen::VectorXd f = Eigen::VectorXd::Zero(3 * ribcage_.mesh.num_nodes());
  AddProfiledTraction(ribcage_.mesh.nodes, patch, load.force_n / area * options_.push_direction, phi, &f);
  return f;
}

std::vector<std::pair<std::int32_t, double>> RibcageFem::SternumLiftTies() const {
  return SternumLiftTiesOf(ribcage_);
}

std::vector<std::pair<std::int32_t, double>> SternumLiftTiesOf(const PatientRibcage& ribcage) {
  const double level = ribcage.measured.slice_z_mm;
  const auto& midline = ribcage.sternum_anterior_midline;
  const Points3& x = ribcage.mesh.nodes;
  for (std::size_t i = 1; i < midline.size(); ++i) {
    const double z0 = x(midline[i - 1], 2), z1 = x(midline[i], 2);
    if ((z0 - level) * (z1 - level) <= 0 && z0 != z1) {
      const double t = (z0 - level) / (z0 - z1);
      return {{midline[i - 1], -(1.0 - t)}, {midline[i], -t}};  // anterior is -y
    }
  }
  ThrowFailure("sternal lift: the measurement slice at z = " + std::to_string(level) + " misses the sternum");
}

double RibcageFem::SternumLift(const Points3& displacement) const {
  double lift = 0.0;
  for (const auto& [node, w] : SternumLiftTies()) lift += w * displacement(node, 1);
  return lift;
}

std::vector<BarResult> RibcageFem::Solve(const std::vector<BarLoad>& loads) const {
  // The model is linear: one solve per distinct bar position with a unit force, then every load case
  // at that position is the unit solution times its force (exact, and 8 times fewer substitutions for
  // the dissertation's 3 x 8 cases).
  std::vector<BarLoad> positions;
  std::vector<std::size_t> position_of(loads.size());
  for (std::size_t i = 0; i < loads.size(); ++i) {
    if (!(loads[i].force_n > 0) || !std::isfinite(loads[i].force_n)) {
      ThrowUsage("bar at " + loads[i].Name() + ": the force must be positive and finite");
    }
    std::size_t k = 0;
    while (k < positions.size() && !(positions[k].position == loads[i].position &&
                                     positions[k].position_in_mm == loads[i].position_in_mm)) {
      ++k;
    }
    if (k == positions.size()) positions.push_back({loads[i].position, loads[i].position_in_mm, 1.0});
    position_of[i] = k;
  }
  std::vector<LoadCase> cases;
  std::vector<Eigen::Index> faces;
  std::vector<double> areas;
  for (const BarLoad& unit : positions) {
    cases.push_back({unit.Name(), NodalForces(unit), {}});
    const Tri6Connectivity patch = ContactPatch(unit);
    faces.push_back(patch.rows());
    areas.push_back(AddProfiledTraction(
        ribcage_.mesh.nodes, patch, Eigen::Vector3d::Zero(),
        [&](const Eigen::Vector3d& x) { return ContactProfile(unit, x.z()); }, nullptr));
  }
  const std::vector<Points3> unit_displacement = solver_->Solve(cases);
  std::vector<double> unit_lift, unit_max;
  for (const Points3& u : unit_displacement) {
    unit_lift.push_back(SternumLift(u));
    unit_max.push_back(u.rowwise().norm().maxCoeff());
  }
  std::vector<BarResult> results(loads.size());
  for (std::size_t i = 0; i < loads.size(); ++i) {
    const std::size_t k = position_of[i];
    const double f = loads[i].force_n;
    results[i].load = loads[i];
    results[i].displacement = f * unit_displacement[k];
    results[i].sternum_lift_mm = f * unit_lift[k];
    results[i].max_displacement_mm = f * unit_max[k];
    results[i].contact_faces = faces[k];
    results[i].contact_area_mm2 = areas[k];
  }
  return results;
}

std::vector<ForceToLift> RibcageFem::ForceToLiftSternum(const std::vector<BarLoad>& positions) const {
  std::vector<BarLoad> unit = positions;
  for (BarLoad& load : unit) load.force_n = 1.0;
  const std::vector<BarResult> results = Solve(unit);
  std::vector<ForceToLift> out;
  for (const BarResult& r : results) {
    ForceToLift f;
    f.position = r.load;
    f.lift_per_newton_mm = r.sternum_lift_mm;
    f.force_n = r.sternum_lift_mm > 0 ? ribcage_.measured.depression_mm / r.sternum_lift_mm
                                      : std::numeric_limits<double>::infinity();
    out.push_back(f);
  }
  return out;
}

}  // namespace pectus::planner
