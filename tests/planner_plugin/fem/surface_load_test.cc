#include "planner_plugin/fem/surface_load.h"

#include <gtest/gtest.h>

#include "planner_plugin/fem/hex_block.h"
#include "shape/core/error.h"

namespace pectus::planner {
namespace {

// The top face (z = 30) of a 40 x 20 x 30 box meshed with quadratic tetrahedra.
struct TopFace {
  TetMesh mesh;
  Tri6Connectivity faces;
  TopFace() {
    Points3 corners;
    Tet4Connectivity tets;
    MakeBoxTetrahedra(4, 2, 3, Eigen::Vector3d(40, 20, 30), &corners, &tets);
    mesh = MakeQuadratic(corners, tets, Eigen::VectorXi::Zero(tets.rows()));
    const MeshBoundary boundary = ExtractBoundary(mesh);
    std::vector<Eigen::Index> top;
    for (Eigen::Index f = 0; f < boundary.faces.rows(); ++f) {
      bool on = true;
      for (int a = 0; a < 3; ++a) on = on && mesh.nodes(boundary.faces(f, a), 2) > 30 - 1e-9;
      if (on) top.push_back(f);
    }
    faces.resize(static_cast<Eigen::Index>(top.size()), 6);
    for (std::size_t k = 0; k < top.size(); ++k)
      faces.row(static_cast<Eigen::Index>(k)) = boundary.faces.row(top[k]);
  }
};

TEST(SurfaceLoad, ConsistentForcesIntegrateTheTractionExactly) {
  const TopFace top;
  EXPECT_NEAR(FacesArea(top.mesh.nodes, top.faces), 800.0, 1e-9);
  Eigen::VectorXd f = Eigen::VectorXd::Zero(3 * top.mesh.num_nodes());
  AddForceOverPatch(top.mesh.nodes, top.faces, Eigen::Vector3d(0, 0, -250), &f);
  EXPECT_NEAR(f.reshaped(3, f.size() / 3).rowwise().sum()(2), -250.0, 1e-9);
  // A quartic profile (degree 4 <= the 7-point rule's 5) integrates exactly: int_0^40 int_0^20 x^2 y^2
  // = (40^3 / 3) (20^3 / 3).
  const auto phi = [](const Eigen::Vector3d& x) { return x.x() * x.x() * x.y() * x.y(); };
  Eigen::VectorXd g = Eigen::VectorXd::Zero(3 * top.mesh.num_nodes());
  const double integral = AddProfiledTraction(top.mesh.nodes, top.faces, Eigen::Vector3d(1, 0, 0), phi, &g);
  EXPECT_NEAR(integral, 64000.0 / 3 * 8000.0 / 3, 1e-6 * integral);
  EXPECT_NEAR(g.reshaped(3, g.size() / 3).rowwise().sum()(0), integral, 1e-9 * integral);
  // Its first moment too: sum_a f_a x_a = int phi x dA for a traction along x (N_a reproduce x).
  double moment = 0;
  for (Eigen::Index n = 0; n < top.mesh.num_nodes(); ++n) moment += g(3 * n) * top.mesh.nodes(n, 0);
  EXPECT_NEAR(moment, 40.0 * 40 * 40 * 40 / 4 * 8000.0 / 3, 1e-3 * moment);
  EXPECT_THROW(AddForceOverPatch(top.mesh.nodes, Tri6Connectivity(0, 6), Eigen::Vector3d(0, 0, 1), &f),
               Error);
}

}  // namespace
}  // namespace pectus::planner
