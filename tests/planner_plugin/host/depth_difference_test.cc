#include "planner_plugin/host/depth_difference.h"

#include <gtest/gtest.h>

#include <cmath>

namespace pectus::planner {
namespace {

// An n x n grid over [0, 100]^2 with heights z = f(x, y), two triangles per cell.
template <typename F>
TriangleMesh Grid(int n, F&& f) {
  TriangleMesh mesh;
  mesh.vertices.positions.resize(n * n, 3);
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      const double x = 100.0 * i / (n - 1), y = 100.0 * j / (n - 1);
      mesh.vertices.positions.row(i * n + j) << x, y, f(x, y);
    }
  }
  mesh.faces.resize(2 * (n - 1) * (n - 1), 3);
  int k = 0;
  for (int i = 0; i + 1 < n; ++i) {
    for (int j = 0; j + 1 < n; ++j) {
      const int a = i * n + j;
      mesh.faces.row(k++) << a, a + n, a + 1;
      mesh.faces.row(k++) << a + 1, a + n, a + n + 1;
    }
  }
  return mesh;
}

TEST(DepthDifference, IsTheHeightOfAPlaneAboveOrBelowEachPoint) {
  // A tilted plane z = 0.5 x + 0.2 y - 7 is exact on any triangulation.
  const TriangleMesh plane = Grid(11, [](double x, double y) { return 0.5 * x + 0.2 * y - 7; });
  Points3 points(4, 3);
  points << 10, 10, 0, 55.5, 33.3, 5, 99, 1, -20, 150, 50, 0;  // the last one is beyond the plane
  const Eigen::VectorXd up = DepthDifference(points, Eigen::Vector3d(0, 0, 1), plane);
  EXPECT_NEAR(up(0), 5 + 2 - 7, 1e-12);
  EXPECT_NEAR(up(1), 0.5 * 55.5 + 0.2 * 33.3 - 7 - 5, 1e-12);
  EXPECT_NEAR(up(2), 0.5 * 99 + 0.2 - 7 + 20, 1e-12);
  EXPECT_TRUE(std::isnan(up(3)));
  // Looking the other way, the sign flips; the direction need not be unit.
  const Eigen::VectorXd down = DepthDifference(points, Eigen::Vector3d(0, 0, -3), plane);
  EXPECT_NEAR(down(0), -up(0), 1e-12);
}

TEST(DepthDifference, ACurvedSurfaceIsMetWithinItsInterpolationErrorAndFoldsGiveTheNearest) {
  const auto dome = [](double x, double y) {
    return 30 - 0.002 * ((x - 50) * (x - 50) + (y - 50) * (y - 50));
  };
  const TriangleMesh mesh = Grid(101, dome);  // 1 mm spacing: linear interpolation within 0.001 mm
  Points3 points(3, 3);
  points << 50, 50, 0, 20.3, 70.7, 10, 80.25, 10.5, 40;
  const Eigen::VectorXd t = DepthDifference(points, Eigen::Vector3d(0, 0, 1), mesh);
  for (Eigen::Index k = 0; k < 3; ++k)
    EXPECT_NEAR(t(k), dome(points(k, 0), points(k, 1)) - points(k, 2), 1e-3);
  // Two layers (a fold): the nearer one counts.
  TriangleMesh two = Grid(3, [](double, double) { return 10.0; });
  const TriangleMesh upper = Grid(3, [](double, double) { return 25.0; });
  const Eigen::Index offset = two.num_vertices();
  two.vertices.positions.conservativeResize(2 * offset, 3);
  two.vertices.positions.bottomRows(offset) = upper.vertices.positions;
  two.faces.conservativeResize(2 * upper.num_faces(), 3);
  two.faces.bottomRows(upper.num_faces()) = upper.faces.array() + static_cast<int>(offset);
  Points3 p(1, 3);
  p << 40, 40, 20;
  EXPECT_NEAR(DepthDifference(p, Eigen::Vector3d(0, 0, 1), two)(0), 5.0, 1e-12);
}

}  // namespace
}  // namespace pectus::planner
