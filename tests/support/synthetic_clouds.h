// Point clouds with a known surface for the reconstruction tests and benchmarks.
#pragma once

#include <cmath>

#include "shape/core/geometry.h"

namespace pectus::testing_support {

/// An ellipsoid with semi-axes (30, 22, 16) mm sampled at n points of a golden-spiral (Fibonacci)
/// lattice, with exact outward unit normals.
inline PointCloud EllipsoidCloud(int n) {
  const Eigen::Vector3d axes(30.0, 22.0, 16.0);
  PointCloud cloud;
  cloud.positions.resize(n, 3);
  cloud.normals.resize(n, 3);
  const double golden = M_PI * (3.0 - std::sqrt(5.0));
  for (int i = 0; i < n; ++i) {
    const double z = 1.0 - 2.0 * (i + 0.5) / n, rho = std::sqrt(1.0 - z * z);
    const Eigen::Vector3d u(rho * std::cos(golden * i), rho * std::sin(golden * i), z);
    cloud.positions.row(i) = u.cwiseProduct(axes).transpose();
    cloud.normals.row(i) = u.cwiseQuotient(axes).normalized().transpose();
  }
  return cloud;
}

}  // namespace pectus::testing_support
