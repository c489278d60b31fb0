#include "shape/surface/cloud_filter.h"

#include <gtest/gtest.h>

#include <cmath>

namespace pectus {
namespace {

TEST(CloudFilter, StatisticalOutlierRemovalDropsStrayPointsOnly) {
  std::vector<Eigen::Vector3d> p;
  for (int i = 0; i < 50; ++i)
    for (int j = 0; j < 50; ++j) p.emplace_back(i, j, 0.0);
  const std::size_t grid = p.size();
  p.emplace_back(25.0, 25.0, 30.0);  // strays off the surface
  p.emplace_back(-40.0, 10.0, 5.0);
  Points3 points(Eigen::Index(p.size()), 3);
  for (std::size_t i = 0; i < p.size(); ++i) points.row(Eigen::Index(i)) = p[i].transpose();
  const auto keep = StatisticalInliers(points, 8, 3.0);
  EXPECT_EQ(keep.size(), grid);
  EXPECT_EQ(keep.back(), grid - 1);
  EXPECT_EQ(StatisticalInliers(points, 0, 3.0).size(), p.size()) << "k = 0: off";
}

TEST(CloudFilter, BlendingMeetsInTheMiddleAndSelectRowsKeepsAttributes) {
  // Two interleaved sheets 0.6 mm apart (a checkerboard of points at z = +-0.3), as two offset sweeps.
  PointCloud c;
  const int side = 81, n = side * side;
  c.positions.resize(n, 3);
  c.normals.resize(n, 3);
  for (int i = 0; i < n; ++i) {
    const int x = i % side, y = i / side;
    c.positions.row(i) << 0.5 * x, 0.5 * y, (x + y) % 2 ? 0.3 : -0.3;
    c.normals.row(i) << 0, 0, 1;
  }
  c.scalars["sweep"] = Eigen::VectorXd::LinSpaced(n, 0, n - 1);
  BlendAlongNormals(3.0, &c);
  for (int i = 0; i < n; ++i) {
    const bool inside =
        c.positions.row(i).head(2).minCoeff() > 5.0 && c.positions.row(i).head(2).maxCoeff() < 35.0;
    if (inside) {
      EXPECT_LT(std::abs(c.positions(i, 2)), 0.03) << "the sheets meet in the middle";
    }
  }
  const PointCloud s = SelectRows(c, {7, 3});
  ASSERT_EQ(s.size(), 2);
  EXPECT_EQ(s.scalars.at("sweep")(0), 7.0);
  EXPECT_EQ(s.normals.rows(), 2);
  EXPECT_EQ(s.positions.row(1), c.positions.row(3));
}

}  // namespace
}  // namespace pectus
