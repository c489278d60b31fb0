// Tests of registration/kdtree.h: the bounded k-nearest search that ICP's certificates rest on, against a
// brute-force scan.
#include "registration/kdtree.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <limits>
#include <random>
#include <utility>
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

// A tree built as two halves (side by side on two threads) answers every query as the whole tree does,
// near the cut between the halves too, and the whole tree answers as a brute-force scan.
TEST(KdTree3, TwoHalvesAnswerAsOneTree) {
  std::mt19937_64 rng(9);
  std::uniform_real_distribution<double> x(0.0, 100.0), y(0.0, 30.0), z(0.0, 10.0);
  Points3 points(2 * KdTree3::kMinHalfPoints + 101, 3);
  for (Eigen::Index i = 0; i < points.rows(); ++i) points.row(i) << x(rng), y(rng), z(rng);
  const KdTree3 whole(points);
  std::vector<KdTree3> moved;  // a tree moves with its halves' nanoflann indices and copied points
  moved.emplace_back(points, 12, /*halves=*/true);
  moved.reserve(moved.capacity() + 1);
  const KdTree3& halves = moved.front();
  ASSERT_EQ(halves.size(), points.rows());
  // Queries anywhere, and within a millimetre of the median along x, where the cut lies.
  std::normal_distribution<double> near_cut(50.0, 0.5);
  for (int q = 0; q < 400; ++q) {
    const Eigen::Vector3d query(q % 2 == 0 ? x(rng) : near_cut(rng), y(rng), z(rng));
    std::uint32_t i1 = 0, i2 = 0;
    double d1 = 0.0, d2 = 0.0;
    ASSERT_TRUE(whole.Nearest(query, &i1, &d1));
    ASSERT_TRUE(halves.Nearest(query, &i2, &d2));
    EXPECT_EQ(i1, i2);
    EXPECT_EQ(d1, d2);
    double brute = std::numeric_limits<double>::infinity();
    for (Eigen::Index i = 0; i < points.rows(); ++i)
      brute = std::min(brute, (points.row(i).transpose() - query).squaredNorm());
    EXPECT_NEAR(d1, brute, 1e-12);
    for (const double radius : {0.2, 0.6, 2.0}) {
      const bool f1 = whole.NearestWithin(query, radius, &i1, &d1);
      ASSERT_EQ(f1, halves.NearestWithin(query, radius, &i2, &d2));
      if (f1) {
        EXPECT_EQ(i1, i2);
      }
      std::uint32_t a[KdTree3::kMaxBounded], b[KdTree3::kMaxBounded];
      double da[KdTree3::kMaxBounded], db[KdTree3::kMaxBounded];
      const int n1 = whole.NearestWithin(query, radius, 3, a, da);
      ASSERT_EQ(n1, halves.NearestWithin(query, radius, 3, b, db));
      for (int j = 0; j < n1; ++j) EXPECT_EQ(a[j], b[j]);
      std::uint32_t two_a[2], two_b[2];
      double two_da[2], two_db[2];
      const int t1 = whole.NearestTwoWithin(query, radius, two_a, two_da);
      ASSERT_EQ(t1, halves.NearestTwoWithin(query, radius, two_b, two_db));
      for (int j = 0; j < t1; ++j) EXPECT_EQ(two_a[j], two_b[j]);
      std::vector<std::pair<std::uint32_t, double>> ra, rb;
      ASSERT_EQ(whole.Radius(query, radius, &ra), halves.Radius(query, radius, &rb));
      EXPECT_EQ(ra, rb);
    }
    std::vector<std::uint32_t> ka, kb;
    std::vector<double> kda, kdb;
    whole.Knn(query, 10, &ka, &kda);
    halves.Knn(query, 10, &kb, &kdb);
    EXPECT_EQ(ka, kb);
    EXPECT_EQ(kda, kdb);
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
