// Shared by the marker test and the trainer's benchmark: marker poses seen by a camera.
#pragma once

#include <Eigen/Geometry>

namespace pectus::trainer::testing {

/// T_camera_marker of a marker facing the camera (its z towards the camera's -z), tilted by `tilt_deg`
/// about an oblique axis, spun by `spin_deg` about its normal, `distance_mm` in front of the camera and a
/// little off its optical axis.
inline Eigen::Isometry3d MarkerFacingCamera(double distance_mm, double tilt_deg, double spin_deg) {
  constexpr double kDeg = 3.14159265358979323846 / 180.0;
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = (Eigen::AngleAxisd(180 * kDeg, Eigen::Vector3d::UnitX()) *
                Eigen::AngleAxisd(tilt_deg * kDeg, Eigen::Vector3d(1, 1, 0).normalized()) *
                Eigen::AngleAxisd(spin_deg * kDeg, Eigen::Vector3d::UnitZ()))
                   .toRotationMatrix();
  T.translation() = Eigen::Vector3d(0.1 * distance_mm, -0.05 * distance_mm, distance_mm);
  return T;
}

}  // namespace pectus::trainer::testing
