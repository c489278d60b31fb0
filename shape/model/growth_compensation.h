// pectus: growth compensation for pre/post comparisons: the similarity that brings the earlier
// (pre-operative) surface to the later one's frame and size, with a given scale or one estimated from
// landmarks (Umeyama 1991, via registration/landmark_alignment.h).
#pragma once

#include <string>
#include <vector>

#include "shape/core/geometry.h"
#include "shape/core/landmarks.h"

namespace pectus {

/// How growth between two visits is compensated.
struct GrowthCompensationOptions {
  /// > 0: the growth scale (size after / size before) is known; rotation and translation still come
  /// from the landmarks. 0 (default): the scale is estimated from the landmarks too.
  double scale = 0.0;

  /// False, with the reason, for a negative or non-finite scale.
  bool IsValid(std::string* why) const;
};

/// What the compensation found.
struct GrowthCompensationResult {
  Similarity3 T_post_pre;           ///< x_post = s R x_pre + t
  double scale = 1.0;               ///< s
  bool estimated = false;           ///< true if s came from the landmarks
  double rms_mm = 0.0;              ///< landmark residual RMS after the transform, mm
  std::vector<std::string> labels;  ///< landmarks used
  std::string message;
};

/// The similarity taking the pre landmarks onto the post landmarks (labels matched, >= 3 in common).
/// Throws Error(kBadInput) naming the sets for fewer than 3 common labels or collinear landmarks,
/// Error(kUsage) for invalid options.
GrowthCompensationResult CompensateGrowth(const LandmarkSet& pre, const LandmarkSet& post,
                                          const GrowthCompensationOptions& options = {},
                                          const std::string& pre_name = "pre landmarks",
                                          const std::string& post_name = "post landmarks");

/// Scaling by s about `centre` (mm): x -> centre + s (x - centre); growth compensation without
/// landmarks for surfaces already registered.
Similarity3 ScaleAbout(const Eigen::Vector3d& centre, double s);

}  // namespace pectus
