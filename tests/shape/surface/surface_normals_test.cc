#include "shape/surface/surface_normals.h"

#include <gtest/gtest.h>

#include <cmath>

#include "shape/core/error.h"

namespace pectus {
namespace {

PointCloud Sphere(int n, double r) {
  PointCloud c;
  c.positions.resize(n, 3);
  const double golden = M_PI * (3.0 - std::sqrt(5.0));
  for (int i = 0; i < n; ++i) {
    const double z = 1.0 - 2.0 * (i + 0.5) / n, rho = std::sqrt(1.0 - z * z);
    c.positions.row(i) << r * rho * std::cos(golden * i), r * rho * std::sin(golden * i), r * z;
  }
  return c;
}

TEST(SurfaceNormals, PropagatedNormalsPointOutOfAClosedObject) {
  const PointCloud c = Sphere(4000, 20.0);
  const KdTree3 tree(c.positions);
  const SurfaceNormalResult r = SurfaceNormals(c, tree, SurfaceNormalOptions{}, "sphere");
  EXPECT_EQ(r.source, "propagated");
  EXPECT_EQ(r.usable, c.size());
  for (Eigen::Index i = 0; i < c.size(); ++i)
    EXPECT_GT(r.normals.row(i).dot(c.positions.row(i)) / 20.0, 0.99);
}

TEST(SurfaceNormals, GivenNormalsAreKeptUnlessMostlyUnusable) {
  PointCloud c = Sphere(1000, 20.0);
  c.normals = -c.positions / 20.0;  // inward, on purpose: given normals are trusted
  const KdTree3 tree(c.positions);
  SurfaceNormalResult r = SurfaceNormals(c, tree, SurfaceNormalOptions{}, "sphere");
  EXPECT_EQ(r.source, "input");
  EXPECT_TRUE(r.normals.isApprox(c.normals));
  c.normals.topRows(500).setZero();
  r = SurfaceNormals(c, tree, SurfaceNormalOptions{}, "sphere");
  EXPECT_EQ(r.source, "propagated");
  SurfaceNormalOptions toward;
  toward.viewpoint = Eigen::Vector3d::Zero();  // a scanner inside: normals point in
  r = SurfaceNormals(c, tree, toward, "sphere");
  EXPECT_EQ(r.source, "viewpoint");
  for (Eigen::Index i = 0; i < c.size(); ++i) EXPECT_LT(r.normals.row(i).dot(c.positions.row(i)), 0.0);
}

TEST(SurfaceNormals, ScanLinesTooFarApartGiveNoNormals) {
  PointCloud c;
  c.positions.resize(2000, 3);
  for (int l = 0; l < 4; ++l)
    for (int i = 0; i < 500; ++i) c.positions.row(l * 500 + i) << 0.1 * i, 15.0 * l, 0.0;
  const KdTree3 tree(c.positions);
  try {
    SurfaceNormals(c, tree, SurfaceNormalOptions{}, "lines.xyz");
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::kBadInput);
    EXPECT_NE(std::string(e.what()).find("lines.xyz"), std::string::npos);
  }
}

}  // namespace
}  // namespace pectus
