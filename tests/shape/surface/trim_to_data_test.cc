#include "shape/surface/trim_to_data.h"

#include <gtest/gtest.h>

#include <cmath>

namespace pectus {
namespace {

// A flat grid mesh over [-50, 50]^2 with step 1 mm.
TriangleMesh Grid() {
  const int n = 101;
  TriangleMesh m;
  m.vertices.positions.resize(n * n, 3);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) m.vertices.positions.row(j * n + i) << i - 50.0, j - 50.0, 0.0;
  m.faces.resize(2 * (n - 1) * (n - 1), 3);
  int f = 0;
  for (int j = 0; j + 1 < n; ++j)
    for (int i = 0; i + 1 < n; ++i) {
      const int a = j * n + i;
      m.faces.row(f++) << a, a + 1, a + n + 1;
      m.faces.row(f++) << a, a + n + 1, a + n;
    }
  return m;
}

// Data on the disc of radius 40 mm, without a disc of diameter `hole` at (10, 0) and with a speck of
// data at (-47, -47) apart from the rest.
Points3 Data(double hole) {
  std::vector<Eigen::Vector3d> p;
  for (double x = -50; x <= 50; x += 0.5)
    for (double y = -50; y <= 50; y += 0.5) {
      if (std::hypot(x, y) > 40.0 || std::hypot(x - 10.0, y) < hole / 2) continue;
      p.emplace_back(x, y, 0.0);
    }
  p.emplace_back(-47.0, -47.0, 0.0);
  Points3 out(Eigen::Index(p.size()), 3);
  for (std::size_t i = 0; i < p.size(); ++i) out.row(Eigen::Index(i)) = p[i].transpose();
  return out;
}

// The grid trimmed to Data(hole) with a 2 mm margin, filling holes up to 20 mm.
TrimResult TrimGrid(double hole, TriangleMesh* mesh) {
  const Points3 data = Data(hole);
  const KdTree3 tree(data);
  *mesh = Grid();
  TrimOptions o;
  o.margin_mm = 2.0;
  o.max_hole_size_mm = 20.0;
  return TrimToData(tree, mesh, o);
}

TEST(TrimToData, KeepsTheScannedRegionAndFillsSmallHoles) {
  TriangleMesh mesh;
  const TrimResult r = TrimGrid(16.0, &mesh);
  EXPECT_EQ(r.holes_filled, 1);
  EXPECT_NEAR(r.largest_hole_filled_mm, 16.0, 2.5);
  EXPECT_EQ(r.components_removed, 1) << "the speck of data at the corner";
  double area = 0;
  for (Eigen::Index f = 0; f < mesh.num_faces(); ++f) {
    const Eigen::Vector3d a = mesh.vertices.positions.row(mesh.faces(f, 0)).transpose();
    const Eigen::Vector3d b = mesh.vertices.positions.row(mesh.faces(f, 1)).transpose();
    const Eigen::Vector3d c = mesh.vertices.positions.row(mesh.faces(f, 2)).transpose();
    area += 0.5 * (b - a).cross(c - a).norm();
    EXPECT_LE(std::hypot(a.x(), a.y()), 40.0 + 2.0 + 1e-9);
  }
  EXPECT_NEAR(area, M_PI * 41.0 * 41.0, 0.03 * M_PI * 41.0 * 41.0) << "the disc plus about half the margin";
  const Eigen::VectorXd& d = mesh.vertices.scalars.at("data_distance");
  EXPECT_EQ(d.size(), mesh.num_vertices());
  EXPECT_GT(d.maxCoeff(), 6.0) << "the filled hole is far from data inside";
}

TEST(TrimToData, WideHolesStayOpen) {
  TriangleMesh mesh;
  const TrimResult r = TrimGrid(30.0, &mesh);
  EXPECT_EQ(r.holes_filled, 0);
  EXPECT_EQ(r.holes_left_open, 1);
  for (Eigen::Index v = 0; v < mesh.num_vertices(); ++v) {
    EXPECT_GT(std::hypot(mesh.vertices.positions(v, 0) - 10.0, mesh.vertices.positions(v, 1)),
              15.0 - 2.0 - 1e-9);
  }
}

}  // namespace
}  // namespace pectus
