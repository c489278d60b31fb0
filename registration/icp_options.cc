// pectus: the options, levels and one-line report of ICP (registration/icp.h).
#include <algorithm>
#include <cmath>
#include <sstream>

#include "registration/icp.h"
#include "shape/core/enum_names.h"
#include "shape/core/error.h"

namespace pectus {

namespace {
constexpr EnumNames<IcpMethod, 2> kMethodNames{
    {{IcpMethod::kPointToPlane, "point-to-plane"}, {IcpMethod::kSymmetric, "symmetric"}}};
}  // namespace

IcpMethod ParseIcpMethod(const std::string& name) {
  return ParseEnum(kMethodNames, name, [&] {
    return "unknown ICP method '" + name + "' (" + ListEnumNames(kMethodNames, "", ", ", ", ") + ")";
  });
}

std::string ToString(IcpMethod method) { return EnumToString(kMethodNames, method, "point-to-plane"); }

bool IcpOptions::IsValid(std::string* why) const {
  auto fail = [&](const std::string& text) {
    if (why) *why = text;
    return false;
  };
  auto positive = [](double v) { return v > 0.0 && std::isfinite(v); };
  if (!positive(min_robust_scale_mm)) return fail("min_robust_scale_mm must be > 0");
  if (!(trim_fraction >= 0.0 && trim_fraction <= 0.9)) return fail("trim_fraction must be in [0, 0.9]");
  if (!(max_normal_angle_deg >= 0.0 && max_normal_angle_deg <= 90.0)) {
    return fail("max_normal_angle_deg must be in [0, 90]");
  }
  if (!(max_tangential_spacings >= 0.0) || !std::isfinite(max_tangential_spacings)) {
    return fail("max_tangential_spacings must be >= 0");
  }
  for (std::size_t i = 0; i < levels.size(); ++i) {
    const IcpLevel& l = levels[i];
    const std::string at = "level " + std::to_string(i + 1) + ": ";
    if (!(l.voxel_size_mm >= 0.0) || !std::isfinite(l.voxel_size_mm)) {
      return fail(at + "voxel_size_mm must be >= 0");
    }
    if (!positive(l.max_distance_mm)) return fail(at + "max_distance_mm must be > 0");
    if (l.max_iterations < 1) return fail(at + "max_iterations must be >= 1");
    if (l.points < 0) return fail(at + "points must be >= 0");
  }
  if (levels.empty()) {
    if (auto_level_points.empty()) return fail("auto_level_points must not be empty when levels is");
    for (int n : auto_level_points) {
      if (n != 0 && n < 10) return fail("auto_level_points must each be >= 10, or 0 for every point");
    }
    if (!positive(initial_max_distance_mm)) return fail("initial_max_distance_mm must be > 0");
    if (!(final_max_distance_mm >= 0.0) || !std::isfinite(final_max_distance_mm)) {
      return fail("final_max_distance_mm must be >= 0");
    }
    if (auto_max_iterations < 1) return fail("auto_max_iterations must be >= 1");
  }
  if (plane_points < 1 || plane_points > kMaxPlanePoints) {
    return fail("plane_points must be in [1, " + std::to_string(kMaxPlanePoints) + "]");
  }
  if (!(target_pose_sd_fraction >= 0.0 && target_pose_sd_fraction < 1.0)) {
    return fail("target_pose_sd_fraction must be in [0, 1) (0: the last sample keeps its size)");
  }
  if (!positive(rotation_tolerance_deg)) return fail("rotation_tolerance_deg must be > 0");
  if (!positive(translation_tolerance_mm)) return fail("translation_tolerance_mm must be > 0");
  if (!patch_centres.empty() && !positive(patch_radius_mm)) {
    return fail("patch_radius_mm must be > 0 with patches");
  }
  for (const auto& c : patch_centres) {
    if (!c.allFinite()) return fail("patch centres must be finite");
  }
  if (!positive(max_rms_mm)) return fail("max_rms_mm must be > 0");
  if (!(min_inlier_fraction >= 0.0 && min_inlier_fraction <= 1.0)) {
    return fail("min_inlier_fraction must be in [0, 1]");
  }
  if (!(inlier_distance_mm >= 0.0) || !std::isfinite(inlier_distance_mm)) {
    return fail("inlier_distance_mm must be >= 0");
  }
  if (!(min_conditioning >= 0.0 && min_conditioning < 1.0)) return fail("min_conditioning must be in [0, 1)");
  if (min_correspondences < 6) return fail("min_correspondences must be >= 6");
  return true;
}

std::string IcpResult::BriefReport() const {
  std::ostringstream s;
  s.precision(3);
  s << (success ? "success" : "FAILED") << ", " << (converged ? "converged" : "not converged") << ", "
    << iterations << " iterations, RMS " << rms_mm << " mm, " << 100.0 * inlier_fraction << " % inliers";
  if (!success) s << ": " << message;
  return s.str();
}

std::vector<IcpLevel> IcpLevelsFor(const IcpOptions& o, Eigen::Index source_points, double spacing) {
  if (!o.levels.empty()) return o.levels;
  std::vector<IcpLevel> levels;
  double gate = o.initial_max_distance_mm;
  const double floor = o.final_max_distance_mm > 0.0 ? o.final_max_distance_mm : 3.0 * spacing;
  for (const int count : o.auto_level_points) {
    IcpLevel l;
    l.points = count > 0 && source_points > count ? count : 0;  // 0: every point
    l.max_distance_mm = std::max(gate, floor);
    l.max_iterations = o.auto_max_iterations;
    levels.push_back(l);
    gate /= 4.0;
  }
  return levels;
}

}  // namespace pectus
