// Area-weighted vertex normals on meshes whose normals are known by construction.
#include "shape/core/per_vertex_normals.h"

#include <gtest/gtest.h>

#include <cmath>

namespace pectus {
namespace {

// A regular octahedron (vertices +-e_i): each vertex lies on four faces of equal area whose normals
// (+-1, +-1, +-1)/sqrt(3) sum to its own direction, so the normal at each vertex is its position. The
// winding is outward; 1e-15 is a few ulps of unit vectors.
TEST(PerVertexNormals, OctahedronVerticesPointOutward) {
  Points3 V(6, 3);
  V << 1, 0, 0, -1, 0, 0, 0, 1, 0, 0, -1, 0, 0, 0, 1, 0, 0, -1;
  Faces3 F(8, 3);
  F << 0, 2, 4, 2, 1, 4, 1, 3, 4, 3, 0, 4,  // upper four, counter-clockwise seen from outside
      2, 0, 5, 1, 2, 5, 3, 1, 5, 0, 3, 5;   // lower four
  const Points3 N = PerVertexNormals(V, F);
  for (int i = 0; i < 6; ++i) EXPECT_LT((N.row(i) - V.row(i)).norm(), 1e-15) << "vertex " << i;
}

// A flat fan of triangles of very different sizes in the plane z = 0, wound counter-clockwise: every normal
// is exactly +z; reversing the winding gives -z.
TEST(PerVertexNormals, PlaneGivesItsNormalAndWindingSetsTheSign) {
  Points3 V(4, 3);
  V << 0, 0, 0, 10, 0, 0, 0, 1, 0, -0.1, -0.1, 0;
  Faces3 F(2, 3);
  F << 0, 1, 2, 0, 2, 3;
  const Points3 N = PerVertexNormals(V, F);
  for (int i = 0; i < 4; ++i) EXPECT_LT((N.row(i) - Eigen::RowVector3d(0, 0, 1)).norm(), 1e-15);
  F.col(1).swap(F.col(2));
  const Points3 M = PerVertexNormals(V, F);
  for (int i = 0; i < 4; ++i) EXPECT_LT((M.row(i) - Eigen::RowVector3d(0, 0, -1)).norm(), 1e-15);
}

// Area weighting: a vertex shared by a large triangle in z = 0 and a small one in x = 0 leans toward the
// large one's normal by the ratio of the areas.
TEST(PerVertexNormals, WeightsFacesByTheirArea) {
  Points3 V(5, 3);
  V << 0, 0, 0, 4, 0, 0, 0, 4, 0,  // triangle of area 8 in z = 0, normal +z
      0, 0, 1, 0, 1, 0;            // with vertex 0: a triangle of area 1/2 in x = 0
  Faces3 F(2, 3);
  F << 0, 1, 2, 0, 4, 3;  // (4 - 0) x (3 - 0) = (0,1,0) x (0,0,1) = (1,0,0): normal +x
  const Points3 N = PerVertexNormals(V, F, Eigen::RowVector3d(7, 7, 7));
  EXPECT_LT((N.row(0) - Eigen::RowVector3d(1, 0, 16).normalized()).norm(), 1e-15);
  EXPECT_LT((N.row(1) - Eigen::RowVector3d(0, 0, 1)).norm(), 1e-15);
  EXPECT_LT((N.row(3) - Eigen::RowVector3d(1, 0, 0)).norm(), 1e-15);
}

TEST(PerVertexNormals, VertexOnNoFaceGetsTheIsolatedValue) {
  Points3 V(5, 3);
  V << 0, 0, 0, 1, 0, 0, 0, 1, 0, 5, 5, 5, 2, 0, 0;
  Faces3 F(2, 3);
  F << 0, 1, 2, 0, 1, 4;  // the second face has zero area
  const Points3 N = PerVertexNormals(V, F, Eigen::RowVector3d(0, 0, 1));
  EXPECT_LT((N.row(3) - Eigen::RowVector3d(0, 0, 1)).norm(), 1e-15);  // on no face
  EXPECT_LT((N.row(4) - Eigen::RowVector3d(0, 0, 1)).norm(), 1e-15);  // only on a zero-area face
  EXPECT_EQ(PerVertexNormals(V, F).row(3).norm(), 0.0);               // default: zero
}

}  // namespace
}  // namespace pectus
