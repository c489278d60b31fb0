// pectus planner host: a plan scored against the average chest (dissertation §4.3, §5.5): the predicted
// chest registered to the average chest by landmarks, the difference between them over the region of
// interest (the average chest's extent: notch to xiphoid, cartilage to cartilage), its RMS and maximum.
// The difference is the depth along the average chest's anterior direction (DepthDifference): how far
// in front of the average chest the predicted chest lies, as a surgeon reads a chest.
//
// Two skin models. "relative" (default; the dissertation's "relative skin model derived from the average
// chest shape", §5.3): the patient's chest is the average chest carrying the patient's deformity and the
// bar's correction, i.e. predicted - average = (predicted skin - the same skin without the deformity),
// both from the ribcage model, measured over the average chest; what the skin model gets wrong about
// soft tissue (pectoral muscles, fat) cancels. "modelled": the modelled skin itself against the average
// chest (its soft-tissue layer is uniform, so a real chest's muscles show as differences).
#pragma once

#include <Eigen/Core>
#include <nlohmann/json.hpp>
#include <string>

#include "planner_plugin/host/average_chest.h"
#include "planner_plugin/host/chest_registration.h"
#include "planner_plugin/host/depth_difference.h"
#include "shape/core/geometry.h"
#include "shape/core/landmarks.h"
#include "shape/model/distance_map.h"

namespace pectus::planner {

/// How a plan is scored.
struct PlanScoreOptions {
  ChestRegistrationOptions registration;
  /// The central region (the middle of the chest, where the dissertation quotes its figures): this
  /// fraction of the region of interest's height (about its middle) and of its width (about the
  /// midline). Default 0.5.
  double central_fraction = 0.5;
  /// Colour the predicted skin too (a second distance map; off in searches). Default true.
  bool map_predicted_skin = true;
  /// The relative skin model (default) or the modelled skin against the average chest (false).
  bool relative = true;
  bool IsValid(std::string* why) const;
};

/// The score of one predicted chest.
struct PlanScore {
  ChestRegistrationResult registration;  ///< T_target_source = T_average_predicted
  /// Per average-chest vertex: the predicted chest minus the average chest along the average chest's
  /// anterior direction (positive: the predicted chest lies in front, over-corrected; negative: still
  /// sunken), mm. NaN where the predicted skin does not reach (not counted).
  Eigen::VectorXd difference_mm;
  Eigen::Matrix<bool, Eigen::Dynamic, 1> central;  ///< per average vertex: in the central region
  DistanceStats roi;                               ///< of difference_mm over the region of interest
  DistanceStats central_roi;                       ///< ... over its central part
  Eigen::Index uncovered = 0;                      ///< average vertices the predicted skin does not reach
  Points3 predicted_in_average;  ///< predicted skin vertices in the average chest's frame, mm
  /// Per predicted skin vertex: the same difference seen from the predicted chest (positive: in front
  /// of the average chest), NaN outside the region of interest (where the average chest does not
  /// reach). Only for the modelled skin with map_predicted_skin (the relative model's predicted chest
  /// is the average chest moved by difference_mm: PredictedChest()).
  Eigen::VectorXd predicted_distance_mm;
  /// {"rms_mm", "max_abs_mm", ..., "central": {...}, "landmark_rms_mm", "scale", "uncovered"}
  nlohmann::json ToJson() const;
};

/// The predicted chest to draw, in the average chest's frame, with its per-vertex difference (mm, NaN
/// outside the region of interest): for the relative skin model, the average chest moved along its
/// anterior direction by difference_mm; for the modelled skin, the predicted skin (faces of `skin`).
TriangleMesh PredictedChest(const PlanScore& score, const AverageChest& average, const TriangleMesh& skin,
                            bool relative, Eigen::VectorXd* difference_mm);

/// The central region of the average chest: per vertex, whether it lies within the middle
/// `fraction` of the sternal length (notch to xiphoid) and of the lateral extent about the midline.
Eigen::Matrix<bool, Eigen::Dynamic, 1> CentralRegion(const AverageChest& average, double fraction);

/// Scores a predicted chest: `skin` (vertices and faces, in the patient's frame) moved into the average
/// chest's frame by `registration` (T_average_patient). `without_deformity`: the same skin's vertices
/// without the deformity (PlannerClient::reference_skin), needed by the relative skin model. A plan
/// registers once, with the patient's reference landmarks (the chest without the deformity), and
/// scores every predicted chest in that one frame, so the bar's correction is measured, not registered
/// away (the skin's own landmarks move with the sternum). Throws Error(kUsage) for the relative model
/// without `without_deformity` of the skin's size.
PlanScore ScorePlan(const TriangleMesh& skin, const Points3& without_deformity,
                    const ChestRegistrationResult& registration, const AverageChest& average,
                    const PlanScoreOptions& options = {});

/// ScorePlan for many predicted chests of one patient (a search): what they share (the average chest's
/// anterior direction and central region, the skin without the deformity in the average frame and its
/// depth) is computed once; Score() then gives exactly what ScorePlan() gives for the skin's faces with
/// those vertices.
class PlanScorer {
 public:
  /// Arguments as ScorePlan's (`skin` gives the faces; its vertices are not used). The scorer keeps
  /// references to `average`, which must outlive it. Throws as ScorePlan.
  PlanScorer(const TriangleMesh& skin, const Points3& without_deformity,
             const ChestRegistrationResult& registration, const AverageChest& average,
             const PlanScoreOptions& options = {});
  /// The score of the skin with vertices `positions` (#skin vertices by 3, patient frame, mm).
  PlanScore Score(const Points3& positions) const;
  /// Score(positions).roi.rms (or .central_roi.rms if `central`) alone, as a search needs it, mm.
  double Rms(const Points3& positions, bool central) const;

  /// A skin linear in the bar's force, skin0 + F skin_per_n (#skin vertices by 3 each, patient frame),
  /// projected once for the depth queries (a search's candidates at one bar position).
  struct LinearSkin {
    DepthProbe::Projected base, per_newton;
  };
  LinearSkin Linearise(const Points3& skin0, const Points3& skin_per_n) const;
  /// Rms() of skin0 + force skin_per_n: the same to round-off (1e-12 mm), without moving the skin.
  double Rms(const LinearSkin& skin, double force_n, bool central) const;

 private:
  const AverageChest* average_;
  PlanScoreOptions options_;
  ChestRegistrationResult registration_;
  TriangleMesh moved_;               // the skin's faces; vertices set per Score()
  Eigen::Vector3d anterior_;         // of the average chest
  DepthProbe probe_;                 // the average chest's vertices along anterior_
  Eigen::VectorXd reference_depth_;  // relative model: depth of the skin without the deformity
  Eigen::Matrix<bool, Eigen::Dynamic, 1> central_;
  double RmsOf(Eigen::VectorXd difference, bool central) const;  // of a depth over the average chest
};

/// Scores `skin` registered by its own `landmarks` (and its anterior direction), with the modelled skin
/// (options.relative is ignored).
PlanScore ScorePlan(const TriangleMesh& skin, const LandmarkSet& landmarks, const AverageChest& average,
                    const PlanScoreOptions& options = {});

}  // namespace pectus::planner
