// pectus: coarse alignment from corresponding points or labelled landmarks (Umeyama 1991).
#pragma once

#include <map>
#include <string>
#include <vector>

#include "shape/core/geometry.h"
#include "shape/core/landmarks.h"

namespace pectus {

/// Options of a least-squares landmark alignment.
struct LandmarkAlignmentOptions {
  /// Estimate a similarity (scale s, rotation, translation) instead of a rigid transform.
  bool estimate_scale = false;
  /// Weight per label (default 1 for a label not listed); weights must be finite and >= 0, and at least
  /// three non-collinear landmarks must keep a positive weight.
  std::map<std::string, double> weights;
  /// The landmarks are degenerate (collinear) when the second principal spread (standard deviation
  /// across the best-fit line, mm) is below this fraction of the first. Default 0.02: three landmarks
  /// 200 mm apart must leave the line by more than about 4 mm.
  double min_spread_ratio = 0.02;
  /// Labels present in only one of the two sets are an error when true; otherwise they are skipped and
  /// listed in the result.
  bool require_all_labels = false;

  /// False, with the reason in `why`, if a value is out of range.
  bool IsValid(std::string* why) const;
};

/// What a landmark alignment found.
struct LandmarkAlignmentResult {
  Similarity3 T_target_source;         ///< x_target = s R x_source + t (s = 1 unless estimate_scale)
  std::vector<std::string> labels;     ///< the labels used, in the source set's order
  Eigen::VectorXd residuals_mm;        ///< |T x_source - x_target| per used label, mm
  double rms_mm = 0.0;                 ///< weighted RMS of the residuals, mm
  std::vector<std::string> unmatched;  ///< labels present in only one set (skipped)
  std::string message;                 ///< one line: labels used, RMS, largest residual
};

/// Weighted least-squares similarity (or rigid) transform taking `source` rows onto `target` rows,
/// Umeyama (1991), "Least-squares estimation of transformation parameters between two point patterns",
/// IEEE TPAMI 13(4), Eqs. (34)-(43), with weights. Solved in doubles about the weighted centroids, so
/// that coordinates far from the origin (a scanner frame kilometres away) lose no precision.
/// @param[in] source   #n by 3 points (mm), n >= 3
/// @param[in] target   #n by 3 corresponding points (mm)
/// @param[in] weights  empty, or #n non-negative weights
/// @param[in] estimate_scale  similarity when true, rigid (s = 1) when false
/// @param[in] min_spread_ratio  see LandmarkAlignmentOptions::min_spread_ratio
/// @param[in] what  names the data in error messages ("landmarks of a.mrk.json")
/// @return T_target_source. Throws Error(kBadInput) naming `what` for fewer than 3 points (with positive
///         weight), mismatched sizes, non-finite values or collinear points.
Similarity3 UmeyamaAlignment(const Points3& source, const Points3& target, const Eigen::VectorXd& weights,
                             bool estimate_scale, double min_spread_ratio = 0.02,
                             const std::string& what = "points");

/// Aligns labelled landmarks: matches them by label, then UmeyamaAlignment. Throws Error(kBadInput)
/// naming `source_name`/`target_name` for fewer than three labels in common (listing the labels found
/// in only one set), a collinear set, an invalid set (duplicate label, non-finite position) or invalid
/// options (Error(kUsage)).
/// @param[in] source       landmarks in the source (moving) frame, mm
/// @param[in] target       landmarks in the target (fixed) frame, mm
/// @param[in] source_name  names the source set in messages (a file name)
/// @param[in] target_name  names the target set in messages
LandmarkAlignmentResult AlignLandmarks(const LandmarkSet& source, const LandmarkSet& target,
                                       const LandmarkAlignmentOptions& options = {},
                                       const std::string& source_name = "moving landmarks",
                                       const std::string& target_name = "fixed landmarks");

}  // namespace pectus
