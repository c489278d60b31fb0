// Test support: rigid poses written the way a test states them (an angle about an axis, then a shift).
#pragma once

#include <Eigen/Geometry>
#include <cmath>

#include "shape/core/geometry.h"

namespace pectus::testing_support {

/// The pose that turns by `deg` degrees about `axis` (through the origin, any length) and then moves by `t`.
inline Rigid3 AxisAnglePose(double deg, const Eigen::Vector3d& axis, const Eigen::Vector3d& t) {
  Rigid3 T = Rigid3::Identity();
  T.linear() = Eigen::AngleAxisd(deg * M_PI / 180.0, axis.normalized()).toRotationMatrix();
  T.translation() = t;
  return T;
}

}  // namespace pectus::testing_support
