#include "registration/estimate_normals.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <random>

#include "shape/core/error.h"
#include "synthetic_chest.h"

namespace pectus {
namespace {

Points3 Plane(int side, double spacing, const Eigen::Vector3d& offset) {
  Points3 p(side * side, 3);
  for (int i = 0; i < side; ++i) {
    for (int j = 0; j < side; ++j)
      p.row(i * side + j) = Eigen::RowVector3d(i * spacing, j * spacing, 0.0) + offset.transpose();
  }
  return p;
}

Points3 Sphere(int count, double radius, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g(0.0, 1.0);
  Points3 p(count, 3);
  for (int i = 0; i < count; ++i) p.row(i) = radius * Eigen::RowVector3d(g(rng), g(rng), g(rng)).normalized();
  return p;
}

// A plane's normals are exactly +z (1e-9) when the viewpoint is above it, also 10 km from the origin.
TEST(EstimateNormals, PlaneTowardViewpointFarFromOrigin) {
  const Eigen::Vector3d offset(1e7, 1e7, -2e6);
  const Points3 p = Plane(40, 1.0, offset);
  NormalOptions o;
  o.viewpoint = offset + Eigen::Vector3d(20, 20, 500);
  const NormalResult r = EstimateNormals(p, o);
  ASSERT_EQ(r.normals.rows(), p.rows());
  EXPECT_EQ(r.num_degenerate, 0);
  for (Eigen::Index i = 0; i < p.rows(); ++i) {
    ASSERT_NEAR(r.normals(i, 2), 1.0, 1e-9) << i;
    EXPECT_NEAR(r.curvature(i), 0.0, 1e-9);
  }
}

// On a densely sampled sphere (r = 100 mm, 20000 points, k = 16) normals are radial within 2 degrees and,
// propagated, all point outward.
TEST(EstimateNormals, SpherePropagatedOutward) {
  const Points3 p = Sphere(20000, 100.0, 3);
  NormalOptions o;
  o.orientation = NormalOrientation::kPropagate;
  const NormalResult r = EstimateNormals(p, o);
  EXPECT_EQ(r.num_components, 1);
  const double cos2 = std::cos(2.0 * 3.14159265358979 / 180.0);
  for (Eigen::Index i = 0; i < p.rows(); ++i) {
    ASSERT_GT(r.normals.row(i).dot(p.row(i).normalized()), cos2) << "point " << i;
  }
}

// On the chest-like surface (30000 points, about 2 mm apart, 0.2 mm noise), propagation orients every
// normal like the analytic outward one; the median angle to it is under 2 degrees and 99 % are within 8.
TEST(EstimateNormals, ChestPropagatedMatchesAnalytic) {
  const PointCloud c = testing::SampleChest(30000, 11, 0.2);
  NormalOptions o;
  o.orientation = NormalOrientation::kPropagate;
  const NormalResult r = EstimateNormals(c.positions, o);
  std::vector<double> angle_deg;
  int agree = 0;
  for (Eigen::Index i = 0; i < c.size(); ++i) {
    const double d = r.normals.row(i).dot(c.normals.row(i));
    agree += d > 0.0;
    angle_deg.push_back(std::acos(std::min(1.0, std::abs(d))) * 180.0 / 3.14159265358979);
  }
  EXPECT_EQ(agree, c.size());
  std::sort(angle_deg.begin(), angle_deg.end());
  EXPECT_LT(angle_deg[angle_deg.size() / 2], 2.0);
  EXPECT_LT(angle_deg[angle_deg.size() * 99 / 100], 8.0);
}

// The same input gives bit-identical output with 1 and 2 threads.
TEST(EstimateNormals, DeterministicAcrossThreads) {
  const PointCloud c = testing::SampleChest(8000, 5, 0.2);
  NormalOptions o;
  o.orientation = NormalOrientation::kPropagate;
  const int threads = omp_get_max_threads();
  omp_set_num_threads(1);
  const NormalResult one = EstimateNormals(c.positions, o);
  omp_set_num_threads(2);
  const NormalResult two = EstimateNormals(c.positions, o);
  omp_set_num_threads(threads);
  EXPECT_TRUE(one.normals == two.normals);
}

// Fewer than 3 neighbours within max_radius_mm gives a zero normal, counted as degenerate.
TEST(EstimateNormals, IsolatedPointsAreDegenerate) {
  Points3 p = Plane(10, 1.0, Eigen::Vector3d::Zero());
  p.conservativeResize(p.rows() + 1, 3);
  p.row(p.rows() - 1) << 500, 500, 500;
  NormalOptions o;
  o.max_radius_mm = 5.0;
  const NormalResult r = EstimateNormals(p, o);
  EXPECT_EQ(r.num_degenerate, 1);
  EXPECT_EQ(r.normals.row(p.rows() - 1).norm(), 0.0);
}

TEST(EstimateNormals, InvalidOptionsAreAUsageError) {
  NormalOptions o;
  o.k = 2;
  std::string why;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_THAT(why, ::testing::HasSubstr("k"));
  try {
    EstimateNormals(Plane(5, 1.0, Eigen::Vector3d::Zero()), o);
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::kUsage);
  }
}

}  // namespace
}  // namespace pectus
