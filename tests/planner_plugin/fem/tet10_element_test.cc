#include "planner_plugin/fem/tet10_element.h"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <random>

#include "planner_plugin/fem/assembly.h"
#include "planner_plugin/fem/hex_block.h"
#include "planner_plugin/fem/linear_elastic_solver.h"
#include "planner_plugin/fem/tet_mesh.h"

namespace pectus::planner {
namespace {

TEST(Tet10Element, ShapeFunctionsAreAPartitionOfUnityAndInterpolateNodes) {
  // Reference positions of the 10 nodes.
  Tet10Nodes ref;
  ref << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0.5, 0, 0, 0.5, 0.5, 0, 0, 0.5, 0, 0, 0, 0.5, 0.5, 0, 0.5, 0,
      0.5, 0.5;
  for (int a = 0; a < 10; ++a) {
    const Eigen::Matrix<double, 10, 1> N = Tet10ShapeFunctions(ref.row(a).transpose());
    for (int b = 0; b < 10; ++b) EXPECT_NEAR(N(b), a == b ? 1.0 : 0.0, 1e-15) << a << " " << b;
  }
  const Eigen::Vector3d xi(0.2, 0.3, 0.1);
  EXPECT_NEAR(Tet10ShapeFunctions(xi).sum(), 1.0, 1e-15);
  EXPECT_LT(Tet10ShapeDerivatives(xi).colwise().sum().norm(), 1e-14);
  // Derivatives against central differences.
  const double h = 1e-6;
  for (int k = 0; k < 3; ++k) {
    Eigen::Vector3d d = Eigen::Vector3d::Zero();
    d(k) = h;
    const Eigen::Matrix<double, 10, 1> fd =
        (Tet10ShapeFunctions(xi + d) - Tet10ShapeFunctions(xi - d)) / (2 * h);
    EXPECT_LT((fd - Tet10ShapeDerivatives(xi).col(k)).norm(), 1e-9);
  }
}

TEST(Tet10Element, StiffnessIsSymmetricWithSixRigidBodyModes) {
  Tet10Nodes X;
  X.topRows<4>() << 0, 0, 0, 10, 1, 0, 2, 9, 1, 1, 2, 8;
  for (int e = 0; e < 6; ++e) X.row(4 + e) = 0.5 * (X.row(kTet10Edges[e][0]) + X.row(kTet10Edges[e][1]));
  const IsotropicMaterial m{"m", 1000.0, 0.3};
  Tet10Stiffness K;
  ASSERT_TRUE(Tet10ElementStiffness(X, m.Elasticity(), &K));
  EXPECT_LT((K - K.transpose()).norm(), 1e-12 * K.norm());
  Eigen::SelfAdjointEigenSolver<Tet10Stiffness> eig(K);
  const Eigen::Matrix<double, 30, 1> ev = eig.eigenvalues();
  for (int i = 0; i < 6; ++i) EXPECT_LT(std::abs(ev(i)), 1e-10 * ev(29)) << "rigid mode " << i;
  EXPECT_GT(ev(6), 1e-6 * ev(29));
  // An inverted element is reported, not integrated.
  X.row(1).swap(X.row(2));
  for (int e = 0; e < 6; ++e) X.row(4 + e) = 0.5 * (X.row(kTet10Edges[e][0]) + X.row(kTet10Edges[e][1]));
  EXPECT_FALSE(Tet10ElementStiffness(X, m.Elasticity(), &K));
}

// Patch test: on a distorted mesh of quadratic tetrahedra, a linear displacement field prescribed on the
// boundary is reproduced exactly (to round-off) at every interior node, and the stress is constant.
TEST(Tet10Element, PatchTestReproducesLinearFieldToMachinePrecision) {
  Points3 corners;
  Tet4Connectivity tets;
  MakeBoxTetrahedra(3, 3, 3, Eigen::Vector3d(30, 30, 30), &corners, &tets);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> jitter(-2.5, 2.5);
  for (Eigen::Index i = 0; i < corners.rows(); ++i) {
    const bool interior = (corners.row(i).array() > 1e-9).all() && (corners.row(i).array() < 30 - 1e-9).all();
    if (interior) corners.row(i) += Eigen::RowVector3d(jitter(rng), jitter(rng), jitter(rng));
  }
  TetMesh mesh = MakeQuadratic(corners, tets, Eigen::VectorXi::Zero(tets.rows()));
  mesh.Validate("patch mesh");
  const MeshBoundary boundary = ExtractBoundary(mesh);
  Eigen::Matrix3d A;
  A << 1e-3, 2e-3, -1e-3, 0.5e-3, -2e-3, 3e-3, 1e-3, 1e-3, 1e-3;
  const Eigen::Vector3d b(0.1, -0.2, 0.3);
  auto field = [&](Eigen::Index node) -> Eigen::Vector3d { return A * mesh.nodes.row(node).transpose() + b; };
  const std::vector<std::int32_t> prescribed = AllDofsOf(boundary.nodes);
  const IsotropicMaterial m{"m", 2000.0, 0.35};
  LinearElasticSolver solver(mesh, {m}, prescribed);
  LoadCase load{"patch", Eigen::VectorXd::Zero(3 * mesh.num_nodes()), Eigen::VectorXd(prescribed.size())};
  for (std::size_t k = 0; k < prescribed.size(); ++k) {
    load.prescribed_values(static_cast<Eigen::Index>(k)) = field(prescribed[k] / 3)(prescribed[k] % 3);
  }
  const Points3 u = solver.Solve({load}).front();
  const std::size_t interior = mesh.num_nodes() - boundary.nodes.size();
  ASSERT_GT(interior, 50u);
  double worst = 0.0;
  for (Eigen::Index i = 0; i < mesh.num_nodes(); ++i) {
    worst = std::max(worst, (u.row(i).transpose() - field(i)).norm());
  }
  EXPECT_LT(worst, 1e-12) << "largest error of the linear field, mm";
  RecordProperty("largest_error_mm", std::to_string(worst));
  // Internal forces balance: no residual force at free nodes, and the reactions sum to zero.
  const Eigen::VectorXd reactions = solver.Reactions(u, load);
  Eigen::Vector3d total = Eigen::Vector3d::Zero();
  for (std::size_t k = 0; k < prescribed.size(); ++k)
    total(prescribed[k] % 3) += reactions(static_cast<Eigen::Index>(k));
  EXPECT_LT(total.norm(), 1e-8 * reactions.cwiseAbs().maxCoeff());
}

}  // namespace
}  // namespace pectus::planner
