// pectus tests: two overlapping noisy samples of the analytic chest and ICP's step-1 problem over them,
// shared by the tests of registration/internal/icp_steps.h and registration/internal/radius_grid.h.
#pragma once

#include <cmath>
#include <cstdint>
#include <vector>

#include "registration/internal/icp_steps.h"
#include "synthetic_chest.h"

namespace pectus::icp_detail::testing {

/// A 20 000-point target and source on the chest (overlapping over most of the source, 0.2 mm noise), the
/// target prepared for ICP, and the source's every row as the sample.
struct ChestPairProblem {
  PointCloud target = pectus::testing::SampleChest(20000, 7, 0.2, -1.3, 0.9);
  PointCloud source = pectus::testing::SampleChest(20000, 8, 0.2, -0.9, 1.3);
  IcpTarget prepared{target.positions, target.normals, "chest"};
  IcpOptions options;
  Eigen::Vector3d origin = source.positions.colwise().mean().transpose();
  Points3 no_normals;

  /// Step 1's problem with `options` (without source normals, the tangential reach three spacings).
  Problem Make() const {
    return Problem{&prepared,
                   &source.positions,
                   &no_normals,
                   origin,
                   &options,
                   -1.0,
                   std::pow(3.0 * prepared.spacing_mm(), 2)};
  }
  /// Every source row, in order.
  std::vector<std::uint32_t> AllRows() const {
    std::vector<std::uint32_t> rows(static_cast<std::size_t>(source.size()));
    for (std::size_t k = 0; k < rows.size(); ++k) rows[k] = static_cast<std::uint32_t>(k);
    return rows;
  }
  /// The source in the target's centred frame.
  Rigid3 Start() const {
    Rigid3 T = Rigid3::Identity();
    T.translation() = origin - prepared.origin();
    return T;
  }
};

}  // namespace pectus::icp_detail::testing
