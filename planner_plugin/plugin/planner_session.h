// pectus planner plugin: one patient's planner behind the C interface (planner_api.h): the patient's
// ribcage fitted to the CT measurements, its finite element model factorised once, the skin over it, and
// the bone surface handed to the host. C++ inside; the C entry points (plugin_entry.cc) wrap every call.
#pragma once

#include <Eigen/Core>
#include <memory>
#include <string>
#include <vector>

#include "planner_plugin/api/planner_api.h"
#include "planner_plugin/io/fem_dataset_h5.h"
#include "planner_plugin/ribcage/bar_response_basis.h"
#include "planner_plugin/ribcage/build_generic_ribcage.h"
#include "planner_plugin/ribcage/build_skin_surface.h"
#include "planner_plugin/ribcage/patient_ribcage.h"
#include "planner_plugin/ribcage/ribcage_fem.h"
#include "shape/core/geometry.h"
#include "shape/core/timings.h"

namespace pectus::planner {

/// Everything the C options set, in the engine's own option structs.
struct PlannerSettings {
  GenericRibcageOptions generic;
  PatientRibcageOptions patient;
  RibcageFemOptions fem;
  SkinSurfaceOptions skin;
};

/// The defaults of planner_api.h's options.
void DefaultPlannerOptions(PectusPlannerOptions* options);
/// The engine's settings from C options (nullptr: defaults). Throws Error(kUsage) naming the bad value.
PlannerSettings SettingsFrom(const PectusPlannerOptions* options);
/// Engine measurements from a C patient. Throws Error(kBadInput) for an unterminated id.
PatientMeasurements MeasurementsFrom(const PectusPlannerPatient& patient);
/// A C patient from a patient table row.
PectusPlannerPatient PatientFrom(const PatientMeasurements& measurements, double ct_haller_index);
/// Engine bar loads from C bars; throws Error(kUsage) for a non-finite value.
std::vector<BarLoad> LoadsFrom(const PectusPlannerBar* bars, std::int64_t count);

/// The bone surface of a ribcage mesh: the corner nodes on its boundary, compacted, with the boundary's
/// corner triangles and each triangle's material region.
struct BoneSurface {
  std::vector<std::int32_t> mesh_nodes;  ///< per surface vertex, its node in the tetrahedral mesh
  Points3 vertices;                      ///< #vertices by 3, mm
  Faces3 faces;                          ///< #faces by 3, outward
  Eigen::VectorXi regions;               ///< #faces RibcageRegion
};

/// Extracts the bone surface of `ribcage`.
BoneSurface MakeBoneSurface(const PatientRibcage& ribcage);

/// One patient's planner (the object behind PectusPlanner*).
class PlannerSession {
 public:
  /// Fits, meshes, factorises and builds the skin. Throws pectus::Error.
  PlannerSession(const PatientMeasurements& patient, const PlannerSettings& settings);
  /// The same from a generic ribcage already built with settings.generic (a cohort's, built once).
  PlannerSession(const GenericRibcage& generic, const PatientMeasurements& patient,
                 const PlannerSettings& settings);

  /// The basis as the FE dataset stores it: its arrays, which points it answers for, and this planner's
  /// fingerprint (BuildBasis() first; throws Error(kUsage) otherwise).
  StoredResponseBasis StoreBasis() const;
  /// Takes a stored basis (ReadStoredResponseBasis) instead of building one. Throws Error(kBadInput)
  /// naming `source` if it was built for another planner (other mesh, skin or options).
  void LoadBasis(const StoredResponseBasis& stored, const std::string& source);

  /// The C measurements struct.
  PectusPlannerMeasurements Measurements() const;
  /// Views of the bone surface (labels: regions) and of the skin (as measured, or without the deformity).
  PectusPlannerMesh BoneMesh() const;
  PectusPlannerMesh SkinMesh(bool without_deformity) const;
  /// Landmarks of a PectusPlannerLandmarkSet: bone, skin (undeformed), reference (undeformed skin's
  /// landmarks moved as the bone would be without depression and torsion). Throws Error(kUsage) for
  /// another set.
  const LandmarkSet& Landmarks(int set) const;

  /// Solves `loads` (one factorisation) and fills the optional outputs (see planner_api.h solve()).
  void Solve(const std::vector<BarLoad>& loads, double* bone_positions, double* skin_positions,
             double* skin_landmarks, PectusPlannerCaseResult* results) const;

  /// The points the basis answers for, in the order of the deform call's outputs: the bone surface's
  /// vertices, the skin's vertices, the skin landmarks (each a fixed combination of mesh nodes).
  std::vector<NodeTies> OutputPoints() const;
  /// Builds the exact response basis of OutputPoints() on the one factorisation, replacing any before
  /// (SessionDeformers of the old one must be gone). Throws pectus::Error for invalid options.
  const BarResponseBasis& BuildBasis(const BarResponseBasisOptions& options);
  /// The basis, or nullptr before BuildBasis().
  const BarResponseBasis* basis() const { return basis_.get(); }
  /// Undeformed positions of OutputPoints(), 3 #points (row-major), mm.
  const Eigen::VectorXd& rest_positions() const { return rest_positions_; }
  Eigen::Index num_bone_vertices() const { return bone_.vertices.rows(); }
  Eigen::Index num_skin_vertices() const { return skin_.mesh.num_vertices(); }
  Eigen::Index num_skin_landmarks() const { return static_cast<Eigen::Index>(skin_landmarks_.size()); }

  const PatientRibcage& ribcage() const { return ribcage_; }
  const RibcageFem& fem() const { return *fem_; }

 private:
  GenericRibcage generic_;
  PatientRibcage ribcage_;
  std::unique_ptr<RibcageFem> fem_;  // refers to ribcage_: declared after it
  SkinSurface skin_;
  LandmarkSet skin_landmarks_, reference_landmarks_;
  Points3 reference_skin_;  // the skin without the deformity
  BoneSurface bone_;
  Timings timings_s_;  // "assembly_and_factorisation", s
  std::unique_ptr<BarResponseBasis> basis_;
  Eigen::VectorXd rest_positions_;        // of OutputPoints(), with basis_
  Eigen::VectorXd RestPositions() const;  // the undeformed OutputPoints(), 3 #points
};

/// One thread's real-time view of a session's basis (the object behind PectusPlannerDeformer): its
/// buffers are sized on construction, so Deform() and LiftForce() never allocate, lock or throw.
class SessionDeformer {
 public:
  /// Throws Error(kUsage) if the session has no basis yet.
  explicit SessionDeformer(const PlannerSession& session);

  /// The deformed bone vertices, skin vertices and skin landmarks (row-major #points by 3, mm; each
  /// nullptr if not wanted) and the sternal lift (mm; nullptr if not wanted) under `bar`. False, with the
  /// outputs untouched and `why` set to a static reason, for a non-finite or non-positive value or a bar
  /// off the sternum.
  bool Deform(const BarLoad& bar, double* bone_positions, double* skin_positions, double* skin_landmarks,
              double* sternum_lift_mm, const char** why) noexcept;
  /// The force that lifts the sternum by `lift_mm` with the bar at `bar`'s position (its force ignored),
  /// N; NaN, with `why`, off the sternum or for a non-finite value.
  double LiftForce(const BarLoad& bar, double lift_mm, const char** why) const noexcept;
  /// The basis's coefficients per newton at `bar`'s position (its force ignored) into `coefficients`
  /// (rank values; the displacement of the output points under force F is F U_r c) and the sternal lift
  /// per newton into `lift_per_n` (either nullptr if not wanted). False, with the outputs untouched and
  /// `why` set, for a non-finite position or a bar off the sternum.
  bool CoefficientsPerNewton(const BarLoad& bar, double* coefficients, double* lift_per_n,
                             const char** why) noexcept;

 private:
  const PlannerSession* session_;
  const BarResponseBasis* basis_;
  BarResponseWorkspace workspace_;
  Eigen::VectorXd displacement_;  // 3 #points
};

}  // namespace pectus::planner
