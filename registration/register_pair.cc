#include "registration/register_pair.h"

#include <cmath>
#include <sstream>

#include "shape/core/error.h"

namespace pectus {
namespace {

double LandmarkRms(const LandmarkAlignmentResult& lm, const LandmarkSet& moving, const LandmarkSet& fixed,
                   const Similarity3& T) {
  double sum = 0.0;
  for (const std::string& label : lm.labels) {
    sum += (T * moving.Find(label)->position - fixed.Find(label)->position).squaredNorm();
  }
  return std::sqrt(sum / static_cast<double>(lm.labels.size()));
}

}  // namespace

bool PairRegistrationOptions::IsValid(std::string* why) const {
  if (!landmarks.IsValid(why) || !icp.IsValid(why) || !normals.IsValid(why)) return false;
  if (!(patch_radius_mm >= 0.0) || !std::isfinite(patch_radius_mm)) {
    if (why) *why = "patch_radius_mm must be >= 0";
    return false;
  }
  const std::pair<const char*, double> limits[] = {
      {"max_landmark_rms_mm", max_landmark_rms_mm},
      {"max_landmark_rms_increase_mm", max_landmark_rms_increase_mm},
      {"max_landmark_shift_mm", max_landmark_shift_mm}};
  for (const auto& [name, value] : limits) {
    if (!(value >= 0.0) || !std::isfinite(value)) {
      if (why) *why = std::string(name) + " must be >= 0 (0: off)";
      return false;
    }
  }
  return true;
}

PairRegistrationResult RegisterPair(const IcpTarget& fixed, const PointCloud& moving,
                                    const LandmarkSet* fixed_landmarks, const LandmarkSet* moving_landmarks,
                                    const Similarity3& initial, const PairRegistrationOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) ThrowUsage("registration: " + why);
  if ((fixed_landmarks == nullptr) != (moving_landmarks == nullptr)) {
    ThrowUsage("registration: landmarks are needed on both scans or on neither");
  }
  const bool with_landmarks = fixed_landmarks != nullptr;
  if (options.patch_radius_mm > 0.0 && !with_landmarks) {
    ThrowUsage("registration: surface patches are placed around landmarks; give landmarks for both scans");
  }
  PairRegistrationResult result;
  result.timings_s.Add(fixed.timings_s());

  // Coarse step: landmarks matched by label (Umeyama), or the given pose.
  Similarity3 T = initial;
  if (with_landmarks) {
    auto t = result.timings_s.Time("landmarks");
    result.landmarks = AlignLandmarks(*moving_landmarks, *fixed_landmarks, options.landmarks,
                                      options.moving_landmarks_name, options.fixed_landmarks_name);
    T = result.landmarks->T_target_source;
  }
  auto finish = [&]() {
    if (with_landmarks)
      result.landmark_rms_mm =
          LandmarkRms(*result.landmarks, *moving_landmarks, *fixed_landmarks, result.T_target_source);
    return result;
  };
  if (!options.refine) {
    result.T_target_source = T;
    result.success = true;
    result.message = with_landmarks ? "landmarks only: " + result.landmarks->message : "initial pose only";
    return finish();
  }

  // Fine step: rigid ICP of the (scaled) moving surface, optionally on patches around its landmarks.
  Points3 scaled;  // the moving scan's points scaled by the landmarks' similarity, when it has a scale
  if (T.scale != 1.0) scaled = T.scale * moving.positions;
  const Points3& source = T.scale != 1.0 ? scaled : moving.positions;
  Points3 source_normals;
  const bool need_normals =
      options.icp.method == IcpMethod::kSymmetric || options.icp.max_normal_angle_deg > 0.0;
  if (need_normals) {
    if (moving.has_normals()) {
      source_normals = moving.normals;
    } else {
      NormalResult n = EstimateNormals(source, options.normals);
      source_normals = std::move(n.normals);
      result.timings_s.Add(n.timings_s);
    }
  }
  IcpOptions icp = options.icp;
  if (options.patch_radius_mm > 0.0) {
    icp.patch_centres.clear();
    for (const std::string& label : result.landmarks->labels) {
      icp.patch_centres.push_back(T.scale * moving_landmarks->Find(label)->position);
    }
    icp.patch_radius_mm = options.patch_radius_mm;
  }
  Rigid3 start_pose = Rigid3::Identity();
  start_pose.linear() = T.rotation;
  start_pose.translation() = T.translation;
  result.icp = AlignIcp(fixed, source, source_normals, start_pose, icp);
  result.timings_s.Add(result.icp->timings_s);
  result.T_target_source.scale = T.scale;
  result.T_target_source.rotation = result.icp->T_target_source.linear();
  result.T_target_source.translation = result.icp->T_target_source.translation();
  result.success = result.icp->success;
  result.message = result.icp->message;
  finish();
  if (with_landmarks) {
    double shift2 = 0.0;
    for (const std::string& label : result.landmarks->labels) {
      const Eigen::Vector3d x = moving_landmarks->Find(label)->position;
      shift2 += (result.T_target_source * x - T * x).squaredNorm();
    }
    result.landmark_shift_mm = std::sqrt(shift2 / static_cast<double>(result.landmarks->labels.size()));
  }
  result.refined = true;  // the fine step's pose, unless the fallback below replaces it
  if (result.success && with_landmarks && options.max_landmark_shift_mm > 0.0 &&
      result.landmark_shift_mm > options.max_landmark_shift_mm) {
    std::ostringstream msg;
    msg.precision(3);
    msg << "the surfaces slid along each other: the fine step moved the landmarks by "
        << result.landmark_shift_mm << " mm RMS from the landmark fit (limit "
        << options.max_landmark_shift_mm
        << " mm); estimate the scale from the landmarks (--scale) if the scans differ in size";
    result.success = false;
    result.message = msg.str();
  }
  if (result.success && with_landmarks && options.max_landmark_rms_increase_mm > 0.0 &&
      result.landmark_rms_mm > result.landmarks->rms_mm + options.max_landmark_rms_increase_mm) {
    std::ostringstream msg;
    msg.precision(3);
    msg << "ICP moved the landmarks " << result.landmark_rms_mm - result.landmarks->rms_mm
        << " mm RMS further from the fixed ones than the landmark fit left them (limit "
        << options.max_landmark_rms_increase_mm << " mm)";
    result.success = false;
    result.message = msg.str();
  }
  if (result.success && with_landmarks && options.max_landmark_rms_mm > 0.0 &&
      result.landmark_rms_mm > options.max_landmark_rms_mm) {
    std::ostringstream msg;
    msg.precision(3);
    msg << "the surfaces slid away from the landmarks: landmark RMS " << result.landmark_rms_mm
        << " mm after the fine step (limit " << options.max_landmark_rms_mm << " mm, "
        << result.landmarks->rms_mm << " mm after the landmark step)";
    result.success = false;
    result.message = msg.str();
  }
  if (!result.success && with_landmarks && options.fall_back_to_landmarks) {
    result.T_target_source = result.landmarks->T_target_source;
    result.landmark_rms_mm = result.landmarks->rms_mm;
    result.refined = false;
    result.success = true;
    result.message = "fine step not kept: " + result.message + "; the landmark pose is used";
  }
  return result;
}

std::string PairRegistrationResult::BriefReport() const {
  std::ostringstream s;
  s.precision(3);
  s << (success ? "success" : "FAILED");
  if (landmarks) s << ", landmarks RMS " << landmarks->rms_mm << " mm";
  if (icp) {
    s << ", ICP " << (refined ? "" : "not kept: ") << icp->iterations << " iterations, RMS " << icp->rms_mm
      << " mm, " << 100.0 * icp->inlier_fraction << " % inliers";
  }
  if (landmarks) s << ", landmark RMS at the end " << landmark_rms_mm << " mm";
  s << ", " << timings_s.Total() << " s";
  if (!success || (icp && !refined)) s << ": " << message;
  return s.str();
}

std::unique_ptr<IcpTarget> PrepareTarget(PointCloud fixed, const PairRegistrationOptions& options,
                                         const std::string& name) {
  if (!fixed.has_normals()) return std::make_unique<IcpTarget>(fixed.positions, options.normals, name);
  return std::make_unique<IcpTarget>(std::move(fixed.positions), std::move(fixed.normals), name,
                                     TargetUse::kSingleAlignment);
}

PairRegistrationResult RegisterPair(const PointCloud& fixed, const PointCloud& moving,
                                    const LandmarkSet* fixed_landmarks, const LandmarkSet* moving_landmarks,
                                    const Similarity3& initial, const PairRegistrationOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) ThrowUsage("registration: " + why);
  const std::unique_ptr<IcpTarget> target = PrepareTarget(fixed, options);
  return RegisterPair(*target, moving, fixed_landmarks, moving_landmarks, initial, options);
}

}  // namespace pectus
