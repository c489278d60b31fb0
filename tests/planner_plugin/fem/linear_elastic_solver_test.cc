#include "planner_plugin/fem/linear_elastic_solver.h"

#include <gtest/gtest.h>

#include "planner_plugin/fem/hex_block.h"
#include "planner_plugin/fem/surface_load.h"
#include "shape/core/error.h"

namespace pectus::planner {
namespace {

// A cantilever beam along x: length L, width b (y), height h (z), clamped at x = 0.
struct Cantilever {
  double L = 200.0, b = 20.0, h = 20.0;
  int nx = 20, ny = 2, nz = 2;
  TetMesh mesh;
  MeshBoundary boundary;
  std::vector<std::int32_t> clamped;
  Tri6Connectivity tip_faces;
  Eigen::Index tip_centre = -1;

  Cantilever() {
    Points3 corners;
    Tet4Connectivity tets;
    MakeBoxTetrahedra(nx, ny, nz, Eigen::Vector3d(L, b, h), &corners, &tets);
    mesh = MakeQuadratic(corners, tets, Eigen::VectorXi::Zero(tets.rows()));
    boundary = ExtractBoundary(mesh);
    std::vector<std::int32_t> root;
    for (Eigen::Index i = 0; i < mesh.num_nodes(); ++i) {
      if (mesh.nodes(i, 0) < 1e-9) root.push_back(static_cast<std::int32_t>(i));
      if ((mesh.nodes.row(i) - Eigen::RowVector3d(L, b / 2, h / 2)).norm() < 1e-9) tip_centre = i;
    }
    clamped = AllDofsOf(root);
    std::vector<Eigen::Index> tip;
    for (Eigen::Index f = 0; f < boundary.faces.rows(); ++f) {
      bool on_tip = true;
      for (int a = 0; a < 3; ++a) on_tip = on_tip && mesh.nodes(boundary.faces(f, a), 0) > L - 1e-9;
      if (on_tip) tip.push_back(f);
    }
    tip_faces.resize(static_cast<Eigen::Index>(tip.size()), 6);
    for (std::size_t k = 0; k < tip.size(); ++k)
      tip_faces.row(static_cast<Eigen::Index>(k)) = boundary.faces.row(tip[k]);
  }

  LoadCase TipLoad(const Eigen::Vector3d& force) const {
    LoadCase load{"tip", Eigen::VectorXd::Zero(3 * mesh.num_nodes()), {}};
    AddForceOverPatch(mesh.nodes, tip_faces, force, &load.nodal_forces);
    return load;
  }
};

// Timoshenko beam theory: tip deflection P L^3 / (3 E I) + P L / (kappa G A), with Cowper's shear
// coefficient kappa = 10 (1 + nu) / (12 + 11 nu) for a rectangle.
double TimoshenkoTipDeflection(double P, double L, double b, double h, const IsotropicMaterial& m) {
  const double I = b * h * h * h / 12.0, A = b * h;
  const double kappa = 10.0 * (1.0 + m.poisson_ratio) / (12.0 + 11.0 * m.poisson_ratio);
  return P * L * L * L / (3.0 * m.youngs_modulus_mpa * I) + P * L / (kappa * m.ShearModulus() * A);
}

TEST(LinearElasticSolver, CantileverTipDeflectionWithinTwoAndAHalfPercentOfTimoshenko) {
  const Cantilever beam;  // two quadratic elements across the height: where linear tetrahedra lock
  const IsotropicMaterial m{"rib", 5000.0, 0.3};
  LinearElasticSolver solver(beam.mesh, {m}, beam.clamped);
  const double P = 100.0;
  const Points3 u = solver.Solve({beam.TipLoad(Eigen::Vector3d(0, 0, -P))}).front();
  const double expected = TimoshenkoTipDeflection(P, beam.L, beam.b, beam.h, m);
  const double got = -u(beam.tip_centre, 2);
  EXPECT_NEAR(got / expected, 1.0, 0.025) << "FE " << got << " mm, Timoshenko " << expected << " mm";
  // Bending in the loaded plane only: the sideways motion (from the mesh's asymmetric diagonals) is tiny.
  EXPECT_LT(std::abs(u(beam.tip_centre, 1)), 1e-3 * got);
  RecordProperty("fe_over_timoshenko", std::to_string(got / expected));
}

TEST(LinearElasticSolver, OneFactorizationServesManyLoadCasesLinearly) {
  const Cantilever beam;
  const IsotropicMaterial m{"cartilage", 20.0, 0.4};
  LinearElasticSolver solver(beam.mesh, {m}, beam.clamped);
  std::vector<LoadCase> cases;
  const double forces[] = {50, 70, 100, 200, 400, 800, 1500, 2000};
  for (double f : forces) cases.push_back(beam.TipLoad(Eigen::Vector3d(0, 0, f * 1e-3)));
  cases.push_back(beam.TipLoad(Eigen::Vector3d(0, 0.05, 0)));
  const std::vector<Points3> u = solver.Solve(cases);
  const std::vector<Points3> more = solver.Solve({cases[2], cases[8]});
  EXPECT_EQ(solver.factorization().factorizations(), 1);
  EXPECT_EQ(solver.factorization().solved_columns(), 11);
  ASSERT_EQ(u.size(), cases.size());
  // Linearity: the displacement scales with the force; equal cases give identical answers.
  for (std::size_t c = 0; c < 8; ++c) {
    EXPECT_LT((u[c] - u[0] * (forces[c] / forces[0])).norm(), 1e-10 * u[c].norm()) << forces[c];
  }
  EXPECT_LT((more[0] - u[2]).norm(), 1e-12 * u[2].norm());
  // Sideways load bends about the other axis.
  const double expected = TimoshenkoTipDeflection(0.05, beam.L, beam.h, beam.b, m);
  EXPECT_NEAR(u[8](beam.tip_centre, 1) / expected, 1.0, 0.025);
  // Equilibrium: the reactions at the clamp balance the applied force.
  const Eigen::VectorXd r = solver.Reactions(u[4], cases[4]);
  double reaction_z = 0.0;
  for (std::size_t k = 0; k < beam.clamped.size(); ++k) {
    if (beam.clamped[k] % 3 == 2) reaction_z += r(static_cast<Eigen::Index>(k));
  }
  EXPECT_NEAR(reaction_z, -0.4, 1e-9);
}

TEST(LinearElasticSolver, UnconstrainedStructureIsReportedNotSolved) {
  const Cantilever beam;
  const IsotropicMaterial m{"m", 100.0, 0.3};
  EXPECT_THROW(LinearElasticSolver(beam.mesh, {m}, {}), Error);
  EXPECT_THROW(LinearElasticSolver(beam.mesh, {IsotropicMaterial{"bad", -1.0, 0.3}}, beam.clamped), Error);
  LinearElasticSolver solver(beam.mesh, {m}, beam.clamped);
  EXPECT_THROW(solver.Solve({LoadCase{"short", Eigen::VectorXd::Zero(3), {}}}), Error);
}

}  // namespace
}  // namespace pectus::planner
