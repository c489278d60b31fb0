// pectus: registration of one scan to another, the analyst's two steps (dissertation, Sec. 4, "All scans
// have to be brought into correspondence"): a coarse alignment from landmarks, then a fine one of the
// surfaces, optionally on circular patches around the landmarks.
#pragma once

#include <memory>
#include <optional>
#include <string>

#include "registration/estimate_normals.h"
#include "registration/icp.h"
#include "registration/landmark_alignment.h"
#include "shape/core/geometry.h"
#include "shape/core/landmarks.h"
#include "shape/core/timings.h"

namespace pectus {

/// Options of RegisterPair.
struct PairRegistrationOptions {
  LandmarkAlignmentOptions landmarks;  ///< coarse step; estimate_scale gives a similarity
  IcpOptions icp;                      ///< fine step (its patch_centres are set from the landmarks)
  bool refine = true;                  ///< run the fine step; false = landmarks (or the initial pose) only
  /// > 0: the fine step uses only the moving scan's points within this radius (mm) of its landmarks,
  /// as the dissertation's surface patches; 0 = the whole surface.
  double patch_radius_mm = 0.0;
  /// The fine step is checked against the landmarks in three ways, each off at 0; a check that fails
  /// rejects the fine step (see fall_back_to_landmarks).
  /// After the fine step, the RMS distance (mm) between the moved landmarks and the fixed ones may not
  /// exceed this: a larger value means the surfaces slid away from what the landmarks say. Scans of one
  /// surface; off (0) for scans of different people, whose landmarks never coincide.
  double max_landmark_rms_mm = 20.0;
  /// The landmark RMS after the fine step may exceed the landmark step's own RMS
  /// (LandmarkAlignmentResult::rms_mm) by at most this (mm): the fine step may not make the landmarks
  /// agree worse than they did by this much. Suits two different chests, whose landmark fit leaves
  /// centimetres.
  double max_landmark_rms_increase_mm = 0.0;
  /// The fine step may move the moving scan's landmarks by at most this RMS distance (mm) from where the
  /// landmark step put them; more means ICP slid the surfaces along each other.
  double max_landmark_shift_mm = 0.0;
  /// When the fine step is rejected (by its own acceptance or a landmark check above) and landmarks were
  /// given: keep the landmark step's pose, with success true, `refined` false and the reason in the
  /// message. False: success false, T_target_source the rejected fine step's pose.
  bool fall_back_to_landmarks = false;
  /// Name the two landmark sets in error messages (their files, say).
  std::string moving_landmarks_name = "moving landmarks";
  std::string fixed_landmarks_name = "fixed landmarks";
  /// Normals for scans that have none (the sign does not matter to ICP).
  NormalOptions normals = [] {
    NormalOptions o;
    o.orientation = NormalOrientation::kNone;
    o.k = 12;
    return o;
  }();

  /// False, with the reason in `why`, if a value is out of range.
  bool IsValid(std::string* why) const;
};

/// What RegisterPair found.
struct PairRegistrationResult {
  Similarity3 T_target_source;                       ///< moving (source) to fixed (target), mm
  std::optional<LandmarkAlignmentResult> landmarks;  ///< the coarse step, when landmarks were given
  std::optional<IcpResult> icp;                      ///< the fine step, when it ran
  double landmark_rms_mm = 0.0;    ///< RMS |T x_moving - x_fixed| over the matched landmarks at the end
  double landmark_shift_mm = 0.0;  ///< RMS distance the fine step moved the moving landmarks (mm)
  bool success = false;            ///< false: the fit is poor, see message
  bool refined = false;            ///< T_target_source is the fine step's (else landmarks or initial)
  std::string message;
  /// Wall time (s): "prepare" (centring the fixed scan, its k-d tree), "normals" (estimating missing
  /// normals of either scan), "landmarks", "icp".
  Timings timings_s;

  /// One line for a log: "success, landmarks RMS 2.1 mm, ICP 14 iterations, RMS 0.21 mm, 97.1 % inliers,
  /// landmark RMS at the end 2.3 mm, 0.52 s", with the message when it failed or the fine step was not kept.
  std::string BriefReport() const;
};

/// Registers `moving` to `fixed`: T_target_source = landmark alignment (when both landmark sets are
/// given, else `initial`), refined by ICP on the surfaces. A scale from the landmarks (estimate_scale)
/// is applied to the moving scan before the rigid fine step. Normals missing from a cloud are estimated.
/// Never reports a poor fit as a success. Throws Error(kBadInput) for unusable landmarks (see
/// AlignLandmarks) and Error(kUsage) for invalid options.
/// @param[in] fixed             target scan (mm); its normals are used if present
/// @param[in] moving            source scan (mm)
/// @param[in] fixed_landmarks   landmarks on the fixed scan, or nullptr
/// @param[in] moving_landmarks  the same labels on the moving scan, or nullptr
/// @param[in] initial           T_target_source to start from when there are no landmarks
PairRegistrationResult RegisterPair(const PointCloud& fixed, const PointCloud& moving,
                                    const LandmarkSet* fixed_landmarks, const LandmarkSet* moving_landmarks,
                                    const Similarity3& initial = {},
                                    const PairRegistrationOptions& options = {});

/// The fixed scan prepared as ICP's target the way RegisterPair prepares it, for one alignment: centred,
/// with its own normals and a coarse sample (TargetUse::kSingleAlignment) if it has normals, else with
/// normals estimated with `options.normals` on its k-d tree. Pass the scan with
/// std::move when it is not needed afterwards: its arrays are then taken over, not copied. Throws
/// Error(kBadInput) naming `name` for a scan ICP cannot use (fewer than 3 points, a non-finite value).
std::unique_ptr<IcpTarget> PrepareTarget(PointCloud fixed, const PairRegistrationOptions& options,
                                         const std::string& name = "fixed scan");

/// The same against a prepared fixed scan (reused across many moving scans, as in a cohort).
PairRegistrationResult RegisterPair(const IcpTarget& fixed, const PointCloud& moving,
                                    const LandmarkSet* fixed_landmarks, const LandmarkSet* moving_landmarks,
                                    const Similarity3& initial = {},
                                    const PairRegistrationOptions& options = {});

}  // namespace pectus
