// Tests of registration/icp_target.cc: a target prepared for one alignment (TargetUse::kSingleAlignment)
// has the spacing a shared target has, to the last bit, a coarse sample of a quarter of its points with
// their own tree, and its tree over every point on request, answering as the shared target's does.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "registration/icp.h"
#include "synthetic_chest.h"

namespace pectus {
namespace {

TEST(IcpTarget, SingleAlignmentKeepsTheSpacingAndSamplesAQuarter) {
  const PointCloud chest = testing::SampleChest(60000, 31, 0.2);
  const IcpTarget shared(chest.positions, chest.normals);
  const IcpTarget single(chest.positions, chest.normals, "chest", TargetUse::kSingleAlignment);
  EXPECT_EQ(shared.coarse(), nullptr);
  ASSERT_NE(single.coarse(), nullptr);
  // The spacing from the grid is the tree's, to the last bit: ICP's levels and gates are unchanged.
  EXPECT_EQ(single.spacing_mm(), shared.spacing_mm());
  EXPECT_GT(single.spacing_mm(), 0.0);

  const CoarseTarget& coarse = *single.coarse();
  // Each row kept with a chance of 1/4: 15000 rows, standard deviation 106.
  EXPECT_NEAR(static_cast<double>(coarse.rows.size()), 15000.0, 500.0);
  EXPECT_TRUE(std::is_sorted(coarse.rows.begin(), coarse.rows.end()));
  EXPECT_TRUE(std::adjacent_find(coarse.rows.begin(), coarse.rows.end()) == coarse.rows.end());
  ASSERT_EQ(coarse.positions.rows(), static_cast<Eigen::Index>(coarse.rows.size()));
  for (std::size_t k = 0; k < coarse.rows.size(); ++k) {
    ASSERT_EQ(coarse.positions.row(static_cast<Eigen::Index>(k)),
              single.centred_positions().row(coarse.rows[k]))
        << "sample point " << k;
  }
  ASSERT_NE(coarse.tree, nullptr);
  EXPECT_EQ(coarse.tree->size(), coarse.positions.rows());
  // A quarter of a surface is sparser than the whole.
  EXPECT_GT(coarse.spacing_mm, 1.1 * single.spacing_mm());

  // The tree over every point, built on request, answers as the shared target's.
  const KdTree3& tree = single.tree();
  ASSERT_EQ(tree.size(), shared.tree().size());
  std::mt19937_64 rng(5);
  std::normal_distribution<double> off(0.0, 2.0);
  for (int q = 0; q < 500; ++q) {
    const auto i = static_cast<Eigen::Index>(rng() % static_cast<std::uint64_t>(chest.size()));
    const Eigen::Vector3d x =
        single.centred_positions().row(i).transpose() + Eigen::Vector3d(off(rng), off(rng), off(rng));
    std::uint32_t a[4], b[4];
    double da[4], db[4];
    ASSERT_EQ(tree.Knn(x, 4, a, da), 4);
    ASSERT_EQ(shared.tree().Knn(x, 4, b, db), 4);
    for (int j = 0; j < 4; ++j) {
      EXPECT_EQ(a[j], b[j]);
      EXPECT_EQ(da[j], db[j]);
    }
  }

  // Under CoarseTarget::kMinPoints points a target is prepared as a shared one.
  const PointCloud small = testing::SampleChest(10000, 31, 0.2);
  const IcpTarget small_single(small.positions, small.normals, "small", TargetUse::kSingleAlignment);
  const IcpTarget small_shared(small.positions, small.normals);
  EXPECT_EQ(small_single.coarse(), nullptr);
  EXPECT_EQ(small_single.spacing_mm(), small_shared.spacing_mm());
}

}  // namespace
}  // namespace pectus
