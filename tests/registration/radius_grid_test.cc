// Tests of registration/internal/radius_grid.h: the grid's k nearest points within a radius are the k-d
// tree's, point for point and to the last bit of the squared distance, and ICP's step 1 finds the same
// pairs with it as without.
#include "registration/internal/radius_grid.h"

#include <gtest/gtest.h>

#include <random>
#include <string>

#include "chest_pair_problem.h"
#include "registration/kdtree.h"

namespace pectus::icp_detail {
namespace {

using testing::ChestPairProblem;

// Queries on the surface, off it by up to 3 mm, in its holes and around and beyond its bounding box, for
// radii up to the cell and k from 1 to 8: the grid answers as the tree does.
TEST(RadiusGrid, AnswersAsTheTreeDoes) {
  const PointCloud chest = pectus::testing::SampleChest(20000, 5, 0.2);
  const KdTree3 tree(chest.positions);
  const double cell = 8.0;  // about three spacings of this sample, as in ICP's finer levels
  const std::optional<RadiusGrid> grid = RadiusGrid::Build(chest.positions, cell, 4 * 20000);
  ASSERT_TRUE(grid.has_value());
  EXPECT_EQ(grid->cell(), cell);
  const Eigen::Vector3d low = chest.positions.colwise().minCoeff().transpose();
  const Eigen::Vector3d high = chest.positions.colwise().maxCoeff().transpose();
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::normal_distribution<double> off(0.0, 1.5);
  std::int64_t found = 0, queries = 0, empty = 0;
  for (int q = 0; q < 6000; ++q) {
    Eigen::Vector3d x;
    if (q % 3 == 2) {  // anywhere in the box grown by two cells each way
      for (int d = 0; d < 3; ++d) x(d) = low(d) - 2 * cell + (high(d) - low(d) + 4 * cell) * unit(rng);
    } else {  // near a point of the surface
      const auto i = static_cast<Eigen::Index>(unit(rng) * static_cast<double>(chest.size()));
      x = chest.positions.row(i).transpose() + Eigen::Vector3d(off(rng), off(rng), off(rng));
    }
    for (const double radius : {0.5, 2.0, 5.0, grid->max_radius()}) {
      for (const int k : {1, 4, 6, 8}) {
        std::uint32_t ti[8], gi[8];
        double td[8], gd[8];
        const int tn = tree.NearestWithin(x, radius, k, ti, td);
        const int gn = grid->NearestWithin(x, radius, k, gi, gd);
        ++queries;
        ASSERT_EQ(gn, tn) << "query " << q << ", radius " << radius << ", k " << k;
        for (int j = 0; j < tn; ++j) {
          ASSERT_EQ(gi[j], ti[j]) << "query " << q << ", radius " << radius << ", k " << k << ", neighbour "
                                  << j;
          ASSERT_EQ(gd[j], td[j]);
        }
        found += tn;
        empty += tn == 0;
      }
    }
  }
  // Both kinds of query were asked: near the surface most find several points, in the box's corners none.
  EXPECT_GT(found, queries);
  EXPECT_GT(empty, queries / 10);
}

// A grid it cannot build is refused, not built badly: no points, a cell that is not a length, or a box so
// large for its points (one outlier a metre off) that it would be mostly empty cells.
TEST(RadiusGrid, RefusesWhatItCannotBin) {
  const PointCloud chest = pectus::testing::SampleChest(2000, 5, 0.2);
  EXPECT_FALSE(RadiusGrid::Build(Points3(0, 3), 1.0, 1000).has_value());
  EXPECT_FALSE(RadiusGrid::Build(chest.positions, 0.0, 1 << 20).has_value());
  EXPECT_FALSE(RadiusGrid::Build(chest.positions, std::nan(""), 1 << 20).has_value());
  EXPECT_TRUE(RadiusGrid::Build(chest.positions, 25.0, 4 * 2000 + 4096).has_value());
  Points3 far = chest.positions;
  far.row(0) += Eigen::RowVector3d(1000.0, 1000.0, 1000.0);
  EXPECT_FALSE(RadiusGrid::Build(far, 25.0, 4 * 2000 + 4096).has_value());
}

// ICP's step 1 with the grid finds the pairs it finds with the tree, with certificates carried from pose
// to pose and without, the grid's cell the search radius as in AlignIcp.
TEST(RadiusGrid, FindPairsUnchanged) {
  const ChestPairProblem chest;
  const IcpTarget& prepared = chest.prepared;
  const Problem tree_only = chest.Make();
  const double gate = 3.0 * prepared.spacing_mm();
  const std::optional<RadiusGrid> grid =
      RadiusGrid::Build(prepared.centred_positions(), kSearchRadiusOverGate * gate * (1.0 + 1e-6), 1 << 22);
  ASSERT_TRUE(grid.has_value());
  Problem with_grid = tree_only;
  with_grid.grid = &*grid;
  const std::vector<std::uint32_t> sample = chest.AllRows();
  NearestCache tree_cache, grid_cache;
  tree_cache.Reset(sample.size(), kSearchRadiusOverGate * gate);
  grid_cache.Reset(sample.size(), kSearchRadiusOverGate * gate);
  std::mt19937_64 rng(12);
  Rigid3 T = chest.Start();
  std::int64_t matched = 0;
  for (const double step : {1.0, 0.1, 0.01, 0.5, 0.002}) {
    T = pectus::testing::RandomPose(&rng, step / 100.0, step, T.translation()) * T;
    Pairs by_tree, by_grid, by_grid_uncached;
    const std::int64_t tree_searches = FindPairs(tree_only, sample, T, gate, &tree_cache, &by_tree);
    const std::int64_t grid_searches = FindPairs(with_grid, sample, T, gate, &grid_cache, &by_grid);
    FindPairs(with_grid, sample, T, gate, nullptr, &by_grid_uncached);
    EXPECT_EQ(grid_searches, tree_searches) << "step " << step << " mm";
    ASSERT_EQ(by_grid.target, by_tree.target) << "step " << step << " mm";
    ASSERT_EQ(by_grid_uncached.target, by_tree.target) << "step " << step << " mm";
    for (std::size_t k = 0; k < sample.size(); ++k) {
      if (by_tree.target[k] == kNoMatch) continue;
      ++matched;
      ASSERT_EQ(by_grid.r[k], by_tree.r[k]) << "point " << k;
      ASSERT_EQ(by_grid.n[k], by_tree.n[k]) << "point " << k;
    }
  }
  EXPECT_GT(matched, 5 * 15000);
}

}  // namespace
}  // namespace pectus::icp_detail
