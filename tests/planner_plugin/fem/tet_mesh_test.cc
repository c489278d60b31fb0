#include "planner_plugin/fem/tet_mesh.h"

#include <gtest/gtest.h>

#include <map>

#include "planner_plugin/fem/hex_block.h"
#include "planner_plugin/fem/surface_load.h"
#include "shape/core/error.h"

namespace pectus::planner {
namespace {

TEST(TetMesh, QuadraticLiftSharesMidEdgeNodesAndBoundaryIsClosed) {
  Points3 corners;
  Tet4Connectivity tets;
  MakeBoxTetrahedra(4, 3, 2, Eigen::Vector3d(40, 30, 20), &corners, &tets);
  const TetMesh mesh = MakeQuadratic(corners, tets, Eigen::VectorXi::Zero(tets.rows()));
  mesh.Validate("box");
  // Nodes of a structured quadratic grid: (2 nx + 1)(2 ny + 1)(2 nz + 1) minus nothing (Kuhn adds only
  // face and body diagonals, whose midpoints are the grid's odd points): 9 * 7 * 5.
  EXPECT_EQ(mesh.num_nodes(), 9 * 7 * 5);
  EXPECT_EQ(mesh.num_tets(), 6 * 4 * 3 * 2);
  const MeshBoundary boundary = ExtractBoundary(mesh);
  // Boundary: 2 triangles per boundary quad.
  EXPECT_EQ(boundary.faces.rows(), 2 * 2 * (4 * 3 + 4 * 2 + 3 * 2));
  EXPECT_NEAR(FacesArea(mesh.nodes, boundary.faces), 2 * (40 * 30 + 40 * 20 + 30 * 20), 1e-9);
  // Closed and consistently oriented: every directed corner edge appears once, its reverse once.
  std::map<std::pair<int, int>, int> directed;
  for (Eigen::Index f = 0; f < boundary.faces.rows(); ++f) {
    for (int i = 0; i < 3; ++i) ++directed[{boundary.faces(f, i), boundary.faces(f, (i + 1) % 3)}];
  }
  for (const auto& [edge, count] : directed) {
    EXPECT_EQ(count, 1);
    EXPECT_EQ(directed.count({edge.second, edge.first}), 1u);
  }
  // Outward: the divergence theorem gives the volume from the boundary triangles.
  const TriangleMesh surface = BoundaryTriangles(boundary, mesh.nodes);
  double volume = 0.0;
  for (Eigen::Index f = 0; f < surface.num_faces(); ++f) {
    const Eigen::Vector3d a = surface.vertices.positions.row(surface.faces(f, 0));
    const Eigen::Vector3d b = surface.vertices.positions.row(surface.faces(f, 1));
    const Eigen::Vector3d c = surface.vertices.positions.row(surface.faces(f, 2));
    volume += a.dot(b.cross(c)) / 6.0;
  }
  EXPECT_NEAR(volume, 40.0 * 30 * 20, 1e-8);
  const Eigen::VectorXd q = RadiusRatios(mesh);
  EXPECT_GT(q.minCoeff(), 0.5);  // Kuhn tetrahedra of a cube: 3 r_in / r_out = 0.717
  EXPECT_LE(q.maxCoeff(), 1.0 + 1e-12);
}

TEST(TetMesh, ValidateNamesTheBadElement) {
  Points3 corners(4, 3);
  corners << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1;
  Tet4Connectivity tets(1, 4);
  tets << 0, 2, 1, 3;  // negative orientation
  const TetMesh mesh = MakeQuadratic(corners, tets, Eigen::VectorXi::Zero(1));
  try {
    mesh.Validate("m.inp");
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("tetrahedron 0"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace pectus::planner
