#include "shape/surface/check_mesh.h"

#include <gtest/gtest.h>

namespace pectus {
namespace {

TriangleMesh Tetrahedron() {
  TriangleMesh m;
  m.vertices.positions.resize(4, 3);
  m.vertices.positions << 0, 0, 0, 10, 0, 0, 0, 10, 0, 0, 0, 10;
  m.faces.resize(4, 3);
  m.faces << 0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3;  // counter-clockwise seen from outside
  return m;
}

TEST(MeshCheck, ClosedTetrahedronIsAWatertightManifold) {
  const MeshCheck c = CheckMesh(Tetrahedron());
  EXPECT_TRUE(c.manifold) << c.message;
  EXPECT_TRUE(c.closed);
  EXPECT_FALSE(c.self_intersecting);
  EXPECT_EQ(c.components, 1);
  EXPECT_EQ(c.border_edges, 0);
  EXPECT_NEAR(c.area_mm2, 3 * 50.0 + std::sqrt(3.0) / 4.0 * 200.0, 1e-9);
}

TEST(MeshCheck, OpenSurfaceHasBorderEdges) {
  TriangleMesh m = Tetrahedron();
  m.faces.conservativeResize(3, 3);
  const MeshCheck c = CheckMesh(m);
  EXPECT_TRUE(c.manifold);
  EXPECT_FALSE(c.closed);
  EXPECT_EQ(c.border_edges, 3);
}

TEST(MeshCheck, FindsSelfIntersectionsAndNonManifoldEdges) {
  TriangleMesh crossing;
  crossing.vertices.positions.resize(6, 3);
  crossing.vertices.positions << 0, 0, 0, 10, 0, 0, 0, 10, 0, 2, 2, -5, 2, 2, 5, 8, 8, 0.5;
  crossing.faces.resize(2, 3);
  crossing.faces << 0, 1, 2, 3, 4, 5;  // the second triangle pierces the first
  const MeshCheck a = CheckMesh(crossing);
  EXPECT_TRUE(a.manifold);
  EXPECT_TRUE(a.self_intersecting);
  EXPECT_FALSE(a.message.empty());

  TriangleMesh fin = Tetrahedron();
  fin.vertices.positions.conservativeResize(5, 3);
  fin.vertices.positions.row(4) << 10, 10, 10;
  fin.faces.conservativeResize(5, 3);
  fin.faces.row(4) << 1, 2, 4;  // a third face on edge 1-2
  EXPECT_FALSE(CheckMesh(fin).manifold);

  TriangleMesh bad = Tetrahedron();
  bad.faces(0, 0) = 9;
  EXPECT_FALSE(CheckMesh(bad).manifold);
}

}  // namespace
}  // namespace pectus
