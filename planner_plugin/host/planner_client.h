// pectus planner host: one patient's planner through the plugin, as C++ (RAII, pectus::Error on
// failure, Eigen arrays). Nothing here knows how the plugin computes; it only speaks planner_api.h.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "planner_plugin/api/planner_api.h"
#include "planner_plugin/host/planner_plugin_loader.h"
#include "shape/core/geometry.h"
#include "shape/core/landmarks.h"

namespace pectus::planner {

/// Throws the pectus::Error matching a plugin status (kind = code, message = the plugin's) unless OK.
void ThrowIfFailed(std::int32_t code, const PectusPlannerStatus& status);

/// A bar placement: position along the sternum from the notch (fraction of the sternal length, or mm)
/// and force.
struct BarPlacement {
  double position = 0.85;
  bool position_in_mm = false;
  double force_n = 200;  ///< N; about the force measured in vivo (docs/planner.md)
  /// "0.85 L, 200 N" or "140 mm, 200 N".
  std::string Name() const;
};

/// The largest sternal lift the linear model is trusted with, mm: twice the depression, and at least 20 mm
/// (for a flat chest). Beyond it a plan over-corrects grossly and the small-displacement model no longer
/// holds: plans flag such scenarios (the placement search's forces end at PlacementSearchOptions::lift_limit
/// times the largest force to lift).
double LinearRangeLiftMm(double depression_mm);

/// One solved placement as the host sees it.
struct PlannedCase {
  BarPlacement bar;
  Points3 bone;                ///< deformed bone surface vertices, mm
  Points3 skin;                ///< deformed skin vertices, mm
  LandmarkSet skin_landmarks;  ///< on the deformed skin
  PectusPlannerCaseResult figures{};
};

/// A patient's planner in the plugin (created on construction, destroyed with this object).
class PlannerClient {
 public:
  /// Creates the planner (fit, mesh, factorisation, skin). Throws the plugin's error as pectus::Error.
  PlannerClient(const PlannerPlugin& plugin, const PectusPlannerPatient& patient,
                const PectusPlannerOptions& options);
  ~PlannerClient();
  PlannerClient(const PlannerClient&) = delete;
  PlannerClient& operator=(const PlannerClient&) = delete;

  const PectusPlannerPatient& patient() const { return patient_; }
  /// The plugin's planner, for calls the client does not wrap (a host's own deformers, timed apart).
  const PectusPlanner* handle() const { return planner_; }
  const PectusPlannerOptions& options() const { return options_; }
  const PectusPlannerMeasurements& measurements() const { return measurements_; }
  /// Undeformed bone surface; face scalars are not kept in TriangleMesh, so regions come separately.
  const TriangleMesh& bone() const { return bone_; }
  const Eigen::VectorXi& bone_regions() const { return bone_regions_; }
  const TriangleMesh& skin() const { return skin_; }
  /// The skin the same ribcage without depression and torsion would carry (vertex by vertex as skin()).
  const Points3& reference_skin() const { return reference_skin_; }
  const LandmarkSet& bone_landmarks() const { return bone_landmarks_; }
  const LandmarkSet& skin_landmarks() const { return skin_landmarks_; }
  /// Where the skin landmarks would be without the deformity: the frame for registering every plan.
  const LandmarkSet& reference_landmarks() const { return reference_landmarks_; }

  /// Solves the placements on the plugin's one factorisation. `with_bone` false skips the bone surface.
  std::vector<PlannedCase> Solve(const std::vector<BarPlacement>& bars, bool with_bone = true) const;
  /// Force to lift the sternum by the depression at each position (force_n of the bars ignored).
  std::vector<PectusPlannerForceToLift> ForceToLift(const std::vector<BarPlacement>& positions) const;

  /// Builds the plugin's exact response basis (interface version 2; seconds): Deform() then answers any
  /// placement in a fraction of a millisecond, matching Solve() to 0.01 mm. `options` nullptr: defaults.
  PectusPlannerBasisSummary BuildBasis(const PectusPlannerBasisOptions* options = nullptr);
  /// Takes the patient's basis from an FE dataset written with bases instead (milliseconds). Throws
  /// Error(kBadInput) naming the file if it has none for this patient or one of another planner.
  PectusPlannerBasisSummary LoadBasis(const std::filesystem::path& dataset);
  bool has_basis() const { return deformer_ != nullptr; }
  /// The placements from the basis (BuildBasis() first): deformed skin, skin landmarks, bone if
  /// `with_bone`, and of the figures only the sternal lift (the others 0). Throws Error(kUsage) for a
  /// bar off the sternum.
  std::vector<PlannedCase> Deform(const std::vector<BarPlacement>& bars, bool with_bone = true) const;
  /// The basis as a table (interface version 4), for a host that evaluates it itself: the modes U_r,
  /// 3 #points by rank (Deform()'s points: bone vertices, skin vertices, skin landmarks; x, y, z of each).
  Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> BasisModes() const;
  /// The coefficients per newton (rank values) of a bar at `bar`'s position into `coefficients` and the
  /// sternal lift per newton (mm/N) into `lift_per_n`: Deform() is the rest plus force U_r c. False off
  /// the sternum; throws Error(kUsage) without a basis.
  bool BasisCoefficients(const BarPlacement& bar, Eigen::VectorXd* coefficients, double* lift_per_n) const;

 private:
  LandmarkSet Landmarks(int set) const;
  const PectusPlannerInterface* api_;
  PectusPlanner* planner_ = nullptr;
  PectusPlannerPatient patient_{};
  PectusPlannerOptions options_{};
  PectusPlannerMeasurements measurements_{};
  TriangleMesh bone_, skin_;
  Points3 reference_skin_;
  Eigen::VectorXi bone_regions_;
  LandmarkSet bone_landmarks_, skin_landmarks_, reference_landmarks_;
  struct DeformerDeleter {
    const PectusPlannerInterface* api;
    void operator()(PectusPlannerDeformer* d) const { api->destroy_deformer(d); }
  };
  std::unique_ptr<PectusPlannerDeformer, DeformerDeleter> deformer_;  // with the basis; before planner_ goes
};

/// Reads one patient of a patient table through the plugin.
PectusPlannerPatient ReadPlannerPatient(const PlannerPlugin& plugin, const std::filesystem::path& table,
                                        const std::string& patient);

/// The plugin's defaults.
PectusPlannerOptions PluginDefaultOptions(const PlannerPlugin& plugin);

/// Writes the FE dataset of every patient of `table` through the plugin; `progress(done, total)`. With
/// `basis` (nullptr: none), every patient's exact response basis too.
PectusPlannerDatasetSummary WritePlannerDataset(
    const PlannerPlugin& plugin, const std::filesystem::path& table, const std::filesystem::path& output,
    const PectusPlannerOptions& options, const std::function<void(std::int64_t, std::int64_t)>& progress,
    const PectusPlannerBasisOptions* basis = nullptr);

/// The learned emulator left one patient out at a time, through the plugin (evaluate_emulator).
struct EmulatorEvaluationReport {
  PectusPlannerEmulatorEvaluation summary{};
  std::vector<PectusPlannerEmulatorPatient> patients;  ///< in the table's order
};

/// Evaluates the emulator on `patients` of `table` (ids separated by commas; empty: all); `progress(done,
/// total)` counts the FE solves, then the folds.
EmulatorEvaluationReport EvaluatePlannerEmulator(
    const PlannerPlugin& plugin, const std::filesystem::path& table, const std::string& patients,
    const PectusPlannerOptions& options, const PectusPlannerEmulatorOptions& emulator,
    const std::function<void(std::int64_t, std::int64_t)>& progress);

}  // namespace pectus::planner
