// Tests of registration/kdtree.h: the bounded k-nearest search that ICP's certificates rest on, against a
// brute-force scan.
#include "registration/kdtree.h"

#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <array>
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

// The nodes of two nanoflann trees are equal, subtree for subtree: the same cuts (axis, and the bounds
// either side) and the same leaves (ranges of the index array).
void ExpectSameNodes(const KdTree3::Index::Node* a, const KdTree3::Index::Node* b, int* nodes) {
  ASSERT_EQ(a->child1 == nullptr, b->child1 == nullptr);
  ++*nodes;
  if (a->child1 == nullptr) {
    ASSERT_EQ(a->node_type.lr.left, b->node_type.lr.left);
    ASSERT_EQ(a->node_type.lr.right, b->node_type.lr.right);
    return;
  }
  ASSERT_EQ(a->node_type.sub.divfeat, b->node_type.sub.divfeat);
  ASSERT_EQ(a->node_type.sub.divlow, b->node_type.sub.divlow);
  ASSERT_EQ(a->node_type.sub.divhigh, b->node_type.sub.divhigh);
  ExpectSameNodes(a->child1, b->child1, nodes);
  ExpectSameNodes(a->child2, b->child2, nodes);
}

// KdTree3 builds the tree nanoflann's own buildIndex builds, node for node and with the points in the same
// order, on one thread and on two, for points spread in a box, on a thin sheet with repeated coordinates
// (ties at every cut), and all alike; and a moved tree answers as before.
TEST(KdTree3, BuildsTheTreeNanoflannBuilds) {
  std::mt19937_64 rng(9);
  std::uniform_real_distribution<double> x(0.0, 100.0), y(0.0, 30.0), z(0.0, 10.0);
  std::uniform_int_distribution<int> grid(0, 40);
  const Eigen::Index n = 40000;
  Points3 box(n, 3), sheet(n, 3), alike(3000, 3);
  for (Eigen::Index i = 0; i < n; ++i) {
    box.row(i) << x(rng), y(rng), z(rng);
    sheet.row(i) << 0.5 * grid(rng), 0.25 * grid(rng), 1e-3 * grid(rng) * grid(rng);
  }
  alike.rowwise() = Eigen::RowVector3d(1.0, -2.0, 3.0);
  const int threads = omp_get_max_threads();
  omp_set_num_threads(2);  // the parallel build uses two threads only where OpenMP allows two
  for (const Points3* points : {&box, &sheet, &alike}) {
    for (const int leaf : {1, 12, 30}) {
      KdTree3::Adaptor adaptor{points};
      const KdTree3::Index reference(3, adaptor, nanoflann::KDTreeSingleIndexAdaptorParams(leaf));
      for (const bool parallel : {false, true}) {
        std::vector<KdTree3> moved;
        moved.emplace_back(*points, leaf, parallel);
        moved.reserve(moved.capacity() + 1);  // the tree moves: its index and adaptor go with it
        const KdTree3::Index& built = moved.front().index();
        SCOPED_TRACE(::testing::Message()
                     << points->rows() << " points, leaf " << leaf << ", parallel " << parallel);
        ASSERT_EQ(built.vAcc, reference.vAcc);
        ASSERT_EQ(built.m_size, reference.m_size);
        for (int i = 0; i < 3; ++i) {
          EXPECT_EQ(built.root_bbox[i].low, reference.root_bbox[i].low);
          EXPECT_EQ(built.root_bbox[i].high, reference.root_bbox[i].high);
        }
        int nodes = 0;
        ExpectSameNodes(built.root_node, reference.root_node, &nodes);
        EXPECT_GE(nodes, 2 * static_cast<int>(points->rows()) / leaf - 1);  // every node was compared
        // The moved tree answers queries as nanoflann's and as a brute-force scan.
        for (int q = 0; q < 50; ++q) {
          const Eigen::Vector3d query(x(rng), y(rng) / 3.0, z(rng) / 2.0);
          std::uint32_t i1 = 0;
          double d1 = 0.0;
          ASSERT_TRUE(moved.front().Nearest(query, &i1, &d1));
          double brute = std::numeric_limits<double>::infinity();
          for (Eigen::Index i = 0; i < points->rows(); ++i)
            brute = std::min(brute, (points->row(i).transpose() - query).squaredNorm());
          EXPECT_NEAR(d1, brute, 1e-9);
          std::vector<std::uint32_t> ka;
          std::vector<double> kda;
          moved.front().Knn(query, 10, &ka, &kda);
          std::array<std::uint32_t, 10> kb{};
          std::array<double, 10> kdb{};
          nanoflann::KNNResultSet<double, std::uint32_t> result(10);
          result.init(kb.data(), kdb.data());
          reference.findNeighbors(result, query.data(), nanoflann::SearchParams());
          for (std::size_t j = 0; j < ka.size(); ++j) {
            EXPECT_EQ(ka[j], kb[j]);
            EXPECT_EQ(kda[j], kdb[j]);
          }
        }
      }
    }
  }
  omp_set_num_threads(threads);
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
