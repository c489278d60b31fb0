#include "shape/model/growth_compensation.h"

#include <cmath>
#include <sstream>

#include "registration/landmark_alignment.h"
#include "shape/core/error.h"

namespace pectus {

bool GrowthCompensationOptions::IsValid(std::string* why) const {
  if (!(scale >= 0.0) || !std::isfinite(scale)) {
    if (why != nullptr) *why = "the growth scale must be > 0 (or 0 to estimate it)";
    return false;
  }
  return true;
}

GrowthCompensationResult CompensateGrowth(const LandmarkSet& pre, const LandmarkSet& post,
                                          const GrowthCompensationOptions& options,
                                          const std::string& pre_name, const std::string& post_name) {
  std::string why;
  if (!options.IsValid(&why)) ThrowUsage(why);
  GrowthCompensationResult result;
  LandmarkAlignmentOptions align;
  if (options.scale > 0.0) {
    // Known scale: scale the pre landmarks, then the rigid fit; x_post = R (s x_pre) + t.
    LandmarkSet scaled = pre;
    for (Landmark& l : scaled.items) l.position *= options.scale;
    align.estimate_scale = false;
    const LandmarkAlignmentResult r = AlignLandmarks(scaled, post, align, pre_name, post_name);
    result.T_post_pre = r.T_target_source;
    result.T_post_pre.scale = options.scale;
    result.scale = options.scale;
    result.rms_mm = r.rms_mm;
    result.labels = r.labels;
  } else {
    align.estimate_scale = true;
    const LandmarkAlignmentResult r = AlignLandmarks(pre, post, align, pre_name, post_name);
    result.T_post_pre = r.T_target_source;
    result.scale = r.T_target_source.scale;
    result.estimated = true;
    result.rms_mm = r.rms_mm;
    result.labels = r.labels;
  }
  std::ostringstream msg;
  msg << "growth scale " << result.scale << (result.estimated ? " (estimated from " : " (given; pose from ")
      << result.labels.size() << " landmarks), landmark RMS " << result.rms_mm << " mm";
  result.message = msg.str();
  return result;
}

Similarity3 ScaleAbout(const Eigen::Vector3d& centre, double s) {
  Similarity3 T;
  T.scale = s;
  T.translation = centre - s * centre;
  return T;
}

}  // namespace pectus
