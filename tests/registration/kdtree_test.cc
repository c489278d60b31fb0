// Tests of registration/kdtree.h: the bounded k-nearest search that ICP's certificates rest on, against a
// brute-force scan.
#include "registration/kdtree.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <vector>

namespace pectus {
namespace {

TEST(KdTree3, NearestWithinMatchesBruteForce) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(0.0, 10.0);
  Points3 points(2000, 3);
  for (Eigen::Index i = 0; i < points.rows(); ++i) points.row(i) << u(rng), u(rng), u(rng);
  const KdTree3 tree(points);
  for (const double radius : {0.3, 1.0, 20.0}) {
    for (int q = 0; q < 200; ++q) {
      const Eigen::Vector3d query(u(rng), u(rng), u(rng));
      std::vector<double> all;
      for (Eigen::Index i = 0; i < points.rows(); ++i) {
        const double d2 = (points.row(i).transpose() - query).squaredNorm();
        if (d2 < radius * radius) all.push_back(d2);
      }
      std::sort(all.begin(), all.end());
      for (const int k : {1, 5, 12}) {  // 12 is clamped to kMaxBounded
        std::uint32_t idx[KdTree3::kMaxBounded];
        double d2[KdTree3::kMaxBounded];
        const int found = tree.NearestWithin(query, radius, k, idx, d2);
        const auto expected = std::min<std::size_t>(all.size(), std::min(k, KdTree3::kMaxBounded));
        ASSERT_EQ(static_cast<std::size_t>(found), expected) << "radius " << radius << ", k " << k;
        for (int j = 0; j < found; ++j) {
          EXPECT_NEAR(d2[j], all[static_cast<std::size_t>(j)], 1e-12);  // the same order of sums to rounding
          EXPECT_NEAR(d2[j], (points.row(idx[j]).transpose() - query).squaredNorm(), 1e-12);
        }
      }
    }
  }
}

TEST(KdTree3, NearestWithinOnAnEmptyTreeFindsNothing) {
  const Points3 none(0, 3);
  const KdTree3 tree(none);
  std::uint32_t idx[4];
  double d2[4];
  EXPECT_EQ(tree.NearestWithin(Eigen::Vector3d::Zero(), 1.0, 4, idx, d2), 0);
}

}  // namespace
}  // namespace pectus
