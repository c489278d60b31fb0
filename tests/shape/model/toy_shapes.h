// Test helper: the hand-checked four-subject example shared by the shape-model and model-quality tests.
#pragma once

#include <Eigen/Core>

namespace pectus::testing {

/// Four one-point "shapes" (3 numbers each): +-a along x and +-b along y, a = 3, b = 1. Mean 0; by hand
/// the covariance is diag(2a^2/3, 2b^2/3, 0) = diag(6, 2/3, 0).
inline Eigen::MatrixXd ToyShapes() {
  Eigen::MatrixXd s(4, 3);
  s << 3, 0, 0, -3, 0, 0, 0, 1, 0, 0, -1, 0;
  return s;
}

}  // namespace pectus::testing
