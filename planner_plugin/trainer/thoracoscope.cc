#include "planner_plugin/trainer/thoracoscope.h"

#include <cmath>

#include "shape/core/error.h"
#include "shape/core/geometry.h"

namespace pectus::trainer {

bool ScopeCameraOptions::IsValid(std::string* why) const {
  const bool ok = oblique_deg >= 0 && oblique_deg <= 70 && horizontal_fov_deg > 10 &&
                  horizontal_fov_deg < 170 && width_px >= 2 && height_px >= 2;
  if (!ok && why != nullptr)
    *why = "scope camera: oblique 0-70 deg, field of view 10-170 deg, at least 2 x 2 pixels";
  return ok;
}

ScopeCamera::ScopeCamera(const ScopeCameraOptions& options) : options_(options) {
  std::string why;
  if (!options.IsValid(&why)) ThrowUsage(why);
  focal_px_ = 0.5 * options.width_px / std::tan(0.5 * options.horizontal_fov_deg * kDegree);
}

Eigen::Matrix3d ScopeCamera::ScopeFromCamera() const {
  // Camera z is the scope's axis turned by the oblique angle towards the scope's -y (the image's top).
  return Eigen::AngleAxisd(options_.oblique_deg * kDegree, Eigen::Vector3d::UnitX()).toRotationMatrix();
}

Eigen::Isometry3d ScopeCamera::SceneFromCamera(const ScopePose& pose) const {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = pose.orientation.toRotationMatrix() * ScopeFromCamera();
  T.translation() = pose.Tip();
  return T;
}

bool ScopeCamera::Project(const ScopePose& pose, const Eigen::Vector3d& point_mm,
                          Eigen::Vector2d* pixel) const noexcept {
  const Eigen::Vector3d p = SceneFromCamera(pose).inverse() * point_mm;
  if (!(p.z() > 1e-9)) return false;
  *pixel = principal_point() + focal_px_ * Eigen::Vector2d(p.x() / p.z(), p.y() / p.z());
  return true;
}

Eigen::Vector3d ScopeCamera::Unproject(const ScopePose& pose, const Eigen::Vector2d& pixel,
                                       double depth_mm) const {
  const Eigen::Vector2d xy = (pixel - principal_point()) / focal_px_;
  return SceneFromCamera(pose) * Eigen::Vector3d(xy.x() * depth_mm, xy.y() * depth_mm, depth_mm);
}

}  // namespace pectus::trainer
