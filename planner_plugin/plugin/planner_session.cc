#include "planner_plugin/plugin/planner_session.h"

#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>

#include "planner_plugin/fem/tet_mesh.h"
#include "shape/core/error.h"

namespace pectus::planner {

void DefaultPlannerOptions(PectusPlannerOptions* options) {
  const RibcageMaterials materials;
  const GenericRibcageOptions generic;
  const SkinSurfaceOptions skin;
  const RibcageFemOptions fem;
  options->sternum_youngs_modulus_mpa = materials.sternum.youngs_modulus_mpa;
  options->sternum_poisson_ratio = materials.sternum.poisson_ratio;
  options->rib_youngs_modulus_mpa = materials.rib.youngs_modulus_mpa;
  options->rib_poisson_ratio = materials.rib.poisson_ratio;
  options->cartilage_youngs_modulus_mpa = materials.cartilage.youngs_modulus_mpa;
  options->cartilage_poisson_ratio = materials.cartilage.poisson_ratio;
  options->contact_width_mm = fem.contact_width_mm;
  options->rib_cell_length_mm = generic.rib_cell_length_mm;
  options->sternum_cells_along = generic.sternum_cells_along;
  options->soft_tissue_mm = skin.soft_tissue_mm;
  options->skin_rows = skin.rows;
  options->skin_columns = skin.columns;
}

PlannerSettings SettingsFrom(const PectusPlannerOptions* options) {
  PectusPlannerOptions o;
  DefaultPlannerOptions(&o);
  if (options != nullptr) o = *options;
  PlannerSettings s;
  s.fem.materials.sternum = {"sternum", o.sternum_youngs_modulus_mpa, o.sternum_poisson_ratio};
  s.fem.materials.rib = {"rib", o.rib_youngs_modulus_mpa, o.rib_poisson_ratio};
  s.fem.materials.cartilage = {"costal_cartilage", o.cartilage_youngs_modulus_mpa, o.cartilage_poisson_ratio};
  s.fem.contact_width_mm = o.contact_width_mm;
  s.generic.rib_cell_length_mm = o.rib_cell_length_mm;
  s.generic.sternum_cells_along = o.sternum_cells_along;
  s.skin.soft_tissue_mm = o.soft_tissue_mm;
  s.skin.rows = o.skin_rows;
  s.skin.columns = o.skin_columns;
  std::string why;
  if (!(o.rib_cell_length_mm >= 2 && o.rib_cell_length_mm <= 20)) {
    char text[160];
    std::snprintf(text, sizeof(text), "planner options: rib_cell_length_mm must be 2 to 20 mm, got %g",
                  o.rib_cell_length_mm);
    ThrowUsage(text);
  }
  if (!s.generic.IsValid(&why)) ThrowUsage("planner options (mesh): " + why);
  if (!s.fem.IsValid(&why)) ThrowUsage("planner options: " + why);
  if (!s.skin.IsValid(&why)) ThrowUsage("planner options (skin): " + why);
  return s;
}

PatientMeasurements MeasurementsFrom(const PectusPlannerPatient& patient) {
  PatientMeasurements m;
  const void* end = std::memchr(patient.id, '\0', sizeof(patient.id));
  if (end == nullptr) ThrowBadInput("patient", "the patient id is not NUL-terminated within 64 bytes");
  m.patient = patient.id;
  CopyCtMeasurements(patient, &m);
  m.haller_index = patient.ct_haller_index;
  m.first_sternum_slice = patient.first_sternum_slice;
  m.last_sternum_slice = patient.last_sternum_slice;
  m.slice_spacing_mm = patient.slice_spacing_mm;
  return m;
}

PectusPlannerPatient PatientFrom(const PatientMeasurements& m, double ct_haller_index) {
  PectusPlannerPatient p{};
  if (m.patient.size() >= sizeof(p.id))
    ThrowBadInput("patient table", "patient id '" + m.patient + "' is too long");
  std::memcpy(p.id, m.patient.c_str(), m.patient.size() + 1);
  CopyCtMeasurements(m, &p);
  p.first_sternum_slice = m.first_sternum_slice;
  p.last_sternum_slice = m.last_sternum_slice;
  p.slice_spacing_mm = m.slice_spacing_mm;
  p.ct_haller_index = ct_haller_index;
  return p;
}

std::vector<BarLoad> LoadsFrom(const PectusPlannerBar* bars, std::int64_t count) {
  if (count < 0 || (count > 0 && bars == nullptr)) ThrowUsage("bars: NULL array or negative count");
  std::vector<BarLoad> loads;
  for (std::int64_t i = 0; i < count; ++i) {
    if (!std::isfinite(bars[i].position) || !std::isfinite(bars[i].force_n)) {
      ThrowUsage("bar " + std::to_string(i) + ": position and force must be finite");
    }
    loads.push_back({bars[i].position, bars[i].position_in_mm != 0, bars[i].force_n});
  }
  return loads;
}

BoneSurface MakeBoneSurface(const PatientRibcage& ribcage) {
  const MeshBoundary boundary = ExtractBoundary(ribcage.mesh);
  BoneSurface out;
  std::vector<std::int32_t> index(static_cast<std::size_t>(ribcage.mesh.num_nodes()), -1);
  out.faces.resize(boundary.faces.rows(), 3);
  out.regions.resize(boundary.faces.rows());
  for (Eigen::Index f = 0; f < boundary.faces.rows(); ++f) {
    for (int i = 0; i < 3; ++i) {
      std::int32_t& k = index[boundary.faces(f, i)];
      if (k < 0) {
        k = static_cast<std::int32_t>(out.mesh_nodes.size());
        out.mesh_nodes.push_back(boundary.faces(f, i));
      }
      out.faces(f, i) = k;
    }
    out.regions(f) = ribcage.mesh.regions(boundary.face_tet(f));
  }
  out.vertices.resize(static_cast<Eigen::Index>(out.mesh_nodes.size()), 3);
  for (std::size_t i = 0; i < out.mesh_nodes.size(); ++i) {
    out.vertices.row(static_cast<Eigen::Index>(i)) = ribcage.mesh.nodes.row(out.mesh_nodes[i]);
  }
  return out;
}

PlannerSession::PlannerSession(const PatientMeasurements& patient, const PlannerSettings& settings)
    : PlannerSession(BuildGenericRibcage(settings.generic), patient, settings) {}

PlannerSession::PlannerSession(const GenericRibcage& generic, const PatientMeasurements& patient,
                               const PlannerSettings& settings)
    : generic_(generic), ribcage_(MakePatientRibcage(generic_, patient, settings.patient)) {
  if (!ribcage_.converged && ribcage_.residual_mm > 1.0) {
    ThrowFailure("the generated ribcage does not reproduce the CT measurements: " + ribcage_.message);
  }
  {
    auto t = timings_s_.Time("assembly_and_factorisation");
    fem_ = std::make_unique<RibcageFem>(ribcage_, settings.fem);
  }
  skin_ = BuildSkinSurface(ribcage_, settings.skin);
  skin_landmarks_ = skin_.Landmarks(skin_.mesh.vertices.positions);
  // The reference: the skin carried by the same ribcage mapped without depression and torsion (the
  // patient's chest without the deformity), and its landmarks (material points of the skin).
  PatientMapParameters undeformed = ribcage_.parameters;
  undeformed.depression_mm = 0;
  undeformed.torsion_rad = 0;
  const TetMesh straight =
      MakeQuadratic(MapGenericNodes(generic_, undeformed, settings.patient.skinning), generic_.tets,
                    generic_.regions);  // same node order as ribcage_.mesh
  reference_skin_ = skin_.Deformed(straight.nodes - ribcage_.mesh.nodes);
  reference_landmarks_ = skin_.Landmarks(reference_skin_);
  bone_ = MakeBoneSurface(ribcage_);
}

const LandmarkSet& PlannerSession::Landmarks(int set) const {
  switch (set) {
    case PECTUS_PLANNER_BONE_LANDMARKS: return ribcage_.landmarks;
    case PECTUS_PLANNER_SKIN_LANDMARKS: return skin_landmarks_;
    case PECTUS_PLANNER_REFERENCE_LANDMARKS: return reference_landmarks_;
    default:
      ThrowUsage("landmarks: set " + std::to_string(set) + " is not 0 (bone), 1 (skin) or 2 (reference)");
  }
}

PectusPlannerMeasurements PlannerSession::Measurements() const {
  const RibcageMeasurements& m = ribcage_.measured;
  PectusPlannerMeasurements out{};
  out.width_mm = m.width_mm;
  out.depth_mm = m.depth_mm;
  out.sternal_length_mm = m.sternal_length_mm;
  out.depression_mm = m.depression_mm;
  out.torsion_deg = m.torsion_deg;
  out.inner_width_mm = m.inner_width_mm;
  out.sternum_to_spine_mm = m.sternum_to_spine_mm;
  out.haller_index = m.haller_index;
  out.slice_z_mm = m.slice_z_mm;
  out.fit_residual_mm = ribcage_.residual_mm;
  out.fit_converged = ribcage_.converged ? 1 : 0;
  out.fit_iterations = ribcage_.iterations;
  out.nodes = ribcage_.mesh.num_nodes();
  out.tets = ribcage_.mesh.num_tets();
  out.free_dofs = fem_->solver().summary().free_dofs;
  out.factorization_seconds = timings_s_.Seconds("assembly_and_factorisation");
  return out;
}

PectusPlannerMesh PlannerSession::BoneMesh() const {
  return {bone_.vertices.rows(), bone_.vertices.data(), bone_.faces.rows(), bone_.faces.data(),
          bone_.regions.data()};
}

PectusPlannerMesh PlannerSession::SkinMesh(bool without_deformity) const {
  const TriangleMesh& m = skin_.mesh;
  const double* positions = without_deformity ? reference_skin_.data() : m.vertices.positions.data();
  return {m.num_vertices(), positions, m.num_faces(), m.faces.data(), nullptr};
}

void PlannerSession::Solve(const std::vector<BarLoad>& loads, double* bone_positions, double* skin_positions,
                           double* skin_landmarks, PectusPlannerCaseResult* results) const {
  const std::vector<BarResult> solved = fem_->Solve(loads);
  const Eigen::Index nb = bone_.vertices.rows(), ns = skin_.mesh.num_vertices();
  const auto nl = static_cast<Eigen::Index>(skin_landmarks_.size());
  for (std::size_t k = 0; k < solved.size(); ++k) {
    const BarResult& r = solved[k];
    const auto kk = static_cast<Eigen::Index>(k);
    if (bone_positions != nullptr) {
      Eigen::Map<Points3> out(bone_positions + kk * nb * 3, nb, 3);
      for (Eigen::Index i = 0; i < nb; ++i)
        out.row(i) = bone_.vertices.row(i) + r.displacement.row(bone_.mesh_nodes[i]);
    }
    if (skin_positions != nullptr || skin_landmarks != nullptr) {
      const Points3 skin = skin_.Deformed(r.displacement);
      if (skin_positions != nullptr) Eigen::Map<Points3>(skin_positions + kk * ns * 3, ns, 3) = skin;
      if (skin_landmarks != nullptr) {
        const LandmarkSet on_skin = skin_.Landmarks(skin);
        Eigen::Map<Points3> out(skin_landmarks + kk * nl * 3, nl, 3);
        for (Eigen::Index i = 0; i < nl; ++i) out.row(i) = on_skin.items[i].position.transpose();
      }
    }
    if (results != nullptr) {
      results[k].sternum_lift_mm = r.sternum_lift_mm;
      results[k].max_displacement_mm = r.max_displacement_mm;
      results[k].bar_level_z_mm = fem_->BarLevelZ(r.load);
      results[k].contact_area_mm2 = r.contact_area_mm2;
      results[k].contact_faces = r.contact_faces;
    }
  }
}

Eigen::VectorXd PlannerSession::RestPositions() const {
  // The skin's ties carry displacements only (the skin lies over the bone, not on its nodes).
  Eigen::VectorXd rest(3 * (num_bone_vertices() + num_skin_vertices() + num_skin_landmarks()));
  Eigen::Index at = 0;
  auto append = [&](const Eigen::Vector3d& p) {
    rest.segment<3>(at) = p;
    at += 3;
  };
  for (Eigen::Index i = 0; i < bone_.vertices.rows(); ++i) append(bone_.vertices.row(i).transpose());
  const Points3& skin = skin_.mesh.vertices.positions;
  for (Eigen::Index i = 0; i < skin.rows(); ++i) append(skin.row(i).transpose());
  for (const Landmark& landmark : skin_landmarks_.items) append(landmark.position);
  return rest;
}

std::vector<NodeTies> PlannerSession::OutputPoints() const {
  std::vector<NodeTies> points;
  points.reserve(bone_.mesh_nodes.size() + skin_.ties.size() + skin_.landmark_points.size());
  for (std::int32_t node : bone_.mesh_nodes) points.push_back({{node, 1.0}});
  points.insert(points.end(), skin_.ties.begin(), skin_.ties.end());
  // A skin landmark is a combination of skin vertices, each a combination of nodes.
  for (const SkinPoint& landmark : skin_.landmark_points) {
    NodeTies ties;
    for (const auto& [vertex, w] : landmark.weights) {
      for (const auto& [node, tie] : skin_.ties[static_cast<std::size_t>(vertex)])
        ties.emplace_back(node, w * tie);
    }
    points.push_back(std::move(ties));
  }
  return points;
}

const BarResponseBasis& PlannerSession::BuildBasis(const BarResponseBasisOptions& options) {
  const std::vector<NodeTies> points = OutputPoints();
  auto basis = std::make_unique<BarResponseBasis>(*fem_, points, options);
  basis_ = std::move(basis);
  rest_positions_ = RestPositions();
  return *basis_;
}

StoredResponseBasis PlannerSession::StoreBasis() const {
  if (!basis_) ThrowUsage("planner: no response basis to store; build it first");
  StoredResponseBasis out;
  out.arrays = basis_->ToStored();
  out.bone_vertices = num_bone_vertices();
  out.skin_vertices = num_skin_vertices();
  out.skin_landmarks = num_skin_landmarks();
  out.mesh_nodes = ribcage_.mesh.num_nodes();
  out.rest_checksum_mm = RestChecksum(rest_positions_);
  return out;
}

void PlannerSession::LoadBasis(const StoredResponseBasis& stored, const std::string& source) {
  Eigen::VectorXd rest = RestPositions();
  const double checksum = RestChecksum(rest);
  if (stored.bone_vertices != num_bone_vertices() || stored.skin_vertices != num_skin_vertices() ||
      stored.skin_landmarks != num_skin_landmarks() || stored.mesh_nodes != ribcage_.mesh.num_nodes() ||
      std::abs(stored.rest_checksum_mm - checksum) > 1e-6 * (1.0 + std::abs(checksum)) ||
      std::abs(stored.arrays.contact_width_mm - fem_->options().contact_width_mm) > 1e-12) {
    ThrowBadInput(source, "the response basis of patient " + ribcage_.patient +
                              " was built for another planner (mesh, skin or contact width differ: " +
                              std::to_string(stored.mesh_nodes) + " nodes and " +
                              std::to_string(stored.skin_vertices) + " skin vertices there, " +
                              std::to_string(ribcage_.mesh.num_nodes()) + " and " +
                              std::to_string(num_skin_vertices()) +
                              " here); build it with the same options, or let the planner build its own");
  }
  auto basis = std::make_unique<BarResponseBasis>(stored.arrays, source);
  // The stiffness: one direct solve's sternal lift against the basis' (other materials differ by percents).
  const BarLoad probe{0.8, false, 1.0};
  const double direct = fem_->ForceToLiftSternum({probe}).front().lift_per_newton_mm;
  const double from_basis = basis->LiftPerNewton(basis->LevelZ(probe));
  if (!(std::abs(direct - from_basis) <= 1e-6 * std::abs(direct))) {
    ThrowBadInput(source, "the response basis of patient " + ribcage_.patient +
                              " was built with other materials (its sternal lift per newton at 0.8 of the "
                              "sternum is " +
                              std::to_string(from_basis) + " mm, this planner's " + std::to_string(direct) +
                              " mm)");
  }
  basis_ = std::move(basis);
  rest_positions_ = std::move(rest);
}

SessionDeformer::SessionDeformer(const PlannerSession& session)
    : session_(&session), basis_(session.basis()) {
  if (basis_ == nullptr)
    ThrowUsage("deformer: the planner has no response basis yet; build it first (build_basis)");
  workspace_ = basis_->MakeWorkspace();
  displacement_.resize(3 * basis_->num_points());
}

bool SessionDeformer::Deform(const BarLoad& bar, double* bone_positions, double* skin_positions,
                             double* skin_landmarks, double* sternum_lift_mm, const char** why) noexcept {
  if (!(std::isfinite(bar.position) && std::isfinite(bar.force_n) && bar.force_n > 0)) {
    *why = "the bar's position and force must be finite and the force positive";
    return false;
  }
  const double level = basis_->LevelZ(bar);
  const Eigen::Index nb = 3 * session_->num_bone_vertices(), ns = 3 * session_->num_skin_vertices(),
                     nl = 3 * session_->num_skin_landmarks();
  // Only the rows asked for: the skin alone is a third of the work of bone and skin.
  const Eigen::Index from = bone_positions ? 0 : skin_positions ? nb : nb + ns;
  const Eigen::Index to = skin_landmarks ? nb + ns + nl : skin_positions ? nb + ns : bone_positions ? nb : 0;
  if (!basis_->Evaluate(level, bar.force_n, &workspace_, displacement_.data(), from, to)) {
    *why = "the bar is off the sternum (its contact profile touches no face of the sternum's back)";
    return false;
  }
  const Eigen::VectorXd& rest = session_->rest_positions();
  auto write = [&](double* out, Eigen::Index first, Eigen::Index count) {
    if (out == nullptr) return;
    for (Eigen::Index i = 0; i < count; ++i) out[i] = rest[first + i] + displacement_[first + i];
  };
  write(bone_positions, 0, nb);
  write(skin_positions, nb, ns);
  write(skin_landmarks, nb + ns, nl);
  if (sternum_lift_mm != nullptr) *sternum_lift_mm = bar.force_n * basis_->LiftPerNewton(level);
  return true;
}

double SessionDeformer::LiftForce(const BarLoad& bar, double lift_mm, const char** why) const noexcept {
  if (!(std::isfinite(bar.position) && std::isfinite(lift_mm))) {
    *why = "the bar's position and the lift must be finite";
    return std::numeric_limits<double>::quiet_NaN();
  }
  const double per_newton = basis_->LiftPerNewton(basis_->LevelZ(bar));
  if (!(per_newton > 0)) {
    *why =
        "a bar there does not lift the sternum at its deepest level (off the sternum, or so near the notch "
        "that it tilts the sternum back)";
    return std::numeric_limits<double>::quiet_NaN();
  }
  return lift_mm / per_newton;
}

bool SessionDeformer::CoefficientsPerNewton(const BarLoad& bar, double* coefficients, double* lift_per_n,
                                            const char** why) noexcept {
  if (!std::isfinite(bar.position)) {
    *why = "the bar's position must be finite";
    return false;
  }
  const double level = basis_->LevelZ(bar);
  if (!basis_->CoefficientsPerNewton(level, &workspace_)) {
    *why = "the bar is off the sternum (its contact profile touches no face of the sternum's back)";
    return false;
  }
  if (coefficients != nullptr) {
    for (Eigen::Index j = 0; j < basis_->rank(); ++j) coefficients[j] = workspace_.coefficients[j];
  }
  if (lift_per_n != nullptr) *lift_per_n = basis_->LiftPerNewton(level);
  return true;
}

}  // namespace pectus::planner
