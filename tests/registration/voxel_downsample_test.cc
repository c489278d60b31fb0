#include "registration/voxel_downsample.h"

#include <gtest/gtest.h>

#include <set>

#include "shape/core/error.h"

namespace pectus {
namespace {

// A 0.25 mm grid over 10 x 10 x 1 mm in 1 mm voxels keeps exactly one point per voxel (100), each inside
// its voxel and nearest to that voxel's mean.
TEST(VoxelDownsample, OnePointPerOccupiedVoxel) {
  Points3 p(40 * 40 * 4, 3);
  Eigen::Index n = 0;
  for (int i = 0; i < 40; ++i)
    for (int j = 0; j < 40; ++j)
      for (int k = 0; k < 4; ++k) p.row(n++) << 0.125 + 0.25 * i, 0.125 + 0.25 * j, 0.125 + 0.25 * k;
  const std::vector<std::uint32_t> kept = VoxelDownsample(p, 1.0);
  ASSERT_EQ(kept.size(), 100u);
  std::set<std::pair<int, int>> cells;
  for (const std::uint32_t r : kept) {
    cells.insert({static_cast<int>(p(r, 0)), static_cast<int>(p(r, 1))});
    // The voxel mean is at .5; the nearest grid points are at .375 or .625.
    EXPECT_NEAR(std::abs(p(r, 0) - std::floor(p(r, 0)) - 0.5), 0.125, 1e-12);
  }
  EXPECT_EQ(cells.size(), 100u);
}

TEST(VoxelDownsample, SubsetAndErrors) {
  Points3 p(3, 3);
  p << 0, 0, 0, 0.1, 0, 0, 5, 5, 5;
  const std::vector<std::uint32_t> subset = {1, 2};
  const std::vector<std::uint32_t> kept = VoxelDownsample(p, 1.0, &subset);
  EXPECT_EQ(kept, (std::vector<std::uint32_t>{1, 2}));
  EXPECT_THROW(VoxelDownsample(p, 0.0), Error);
  EXPECT_THROW(VoxelDownsample(p, 1e-9), Error);  // 2^21 cells exceeded
}

TEST(MedianPointSpacing, RegularGrid) {
  Points3 p(30 * 30, 3);
  for (int i = 0; i < 30; ++i)
    for (int j = 0; j < 30; ++j) p.row(i * 30 + j) << 0.7 * i, 0.7 * j, 0.0;
  const KdTree3 tree(p);
  EXPECT_NEAR(MedianPointSpacing(p, tree), 0.7, 1e-12);
}

}  // namespace
}  // namespace pectus
