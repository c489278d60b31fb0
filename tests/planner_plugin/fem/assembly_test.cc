// Global stiffness assembly: the sparse lower triangle and the split blocks against a dense sum of the
// element matrices, the six rigid-body modes in the null space of the unconstrained stiffness, and a
// uniaxial bar whose displacement and end force are known in closed form.
#include "planner_plugin/fem/assembly.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <Eigen/SparseCholesky>
#include <vector>

#include "planner_plugin/fem/hex_block.h"
#include "planner_plugin/fem/tet10_element.h"
#include "shape/core/error.h"

namespace pectus::planner {
namespace {

// A box of quadratic tetrahedra, cells split in two regions along x.
TetMesh Box(int nx, int ny, int nz, const Eigen::Vector3d& size) {
  Points3 corners;
  Tet4Connectivity tets;
  MakeBoxTetrahedra(nx, ny, nz, size, &corners, &tets);
  Eigen::VectorXi regions(tets.rows());
  for (Eigen::Index t = 0; t < tets.rows(); ++t) {
    double x = 0;
    for (int a = 0; a < 4; ++a) x += corners(tets(t, a), 0) / 4;
    regions(t) = x < size.x() / 2 ? 0 : 1;
  }
  return MakeQuadratic(corners, tets, regions);
}

const std::vector<IsotropicMaterial> kMaterials = {{"soft", 100.0, 0.4}, {"stiff", 5000.0, 0.3}};

// K = sum_e K_e, the element matrices added one by one into a dense matrix.
Eigen::MatrixXd DenseStiffness(const TetMesh& mesh, const std::vector<IsotropicMaterial>& materials) {
  Eigen::MatrixXd K = Eigen::MatrixXd::Zero(3 * mesh.num_nodes(), 3 * mesh.num_nodes());
  for (Eigen::Index t = 0; t < mesh.num_tets(); ++t) {
    Tet10Nodes X;
    for (int a = 0; a < 10; ++a) X.row(a) = mesh.nodes.row(mesh.tets(t, a));
    Tet10Stiffness Ke;
    EXPECT_TRUE(Tet10ElementStiffness(X, materials[mesh.regions(t)].Elasticity(), &Ke));
    for (int a = 0; a < 30; ++a) {
      for (int b = 0; b < 30; ++b)
        K(Dof(mesh.tets(t, a / 3), a % 3), Dof(mesh.tets(t, b / 3), b % 3)) += Ke(a, b);
    }
  }
  return K;
}

// The full symmetric matrix from its stored lower triangle.
Eigen::MatrixXd FromLower(const Eigen::SparseMatrix<double>& lower) {
  const Eigen::MatrixXd L = Eigen::MatrixXd(lower);
  Eigen::MatrixXd full = L + L.transpose();
  full.diagonal() = L.diagonal();
  return full;
}

// The summation order differs from the dense one (parallel, atomic adds): equal to round-off, 1e-12 of
// the largest entry.
TEST(AssembleStiffness, EqualsTheDenseSumOfElementMatricesAndIsSymmetric) {
  const TetMesh mesh = Box(2, 2, 1, Eigen::Vector3d(20, 10, 5));
  const DofPartition all_free(mesh.num_nodes(), {});
  const AssembledStiffness K = AssembleStiffness(mesh, kMaterials, all_free);
  ASSERT_EQ(K.K_ff_lower.rows(), 3 * mesh.num_nodes());
  const Eigen::MatrixXd dense = DenseStiffness(mesh, kMaterials);
  const double scale = dense.cwiseAbs().maxCoeff();
  EXPECT_LT((dense - dense.transpose()).cwiseAbs().maxCoeff(), 1e-12 * scale);
  EXPECT_LT((FromLower(K.K_ff_lower) - dense).cwiseAbs().maxCoeff(), 1e-12 * scale);
  // Only the lower triangle is stored.
  for (int j = 0; j < K.K_ff_lower.outerSize(); ++j) {
    for (Eigen::SparseMatrix<double>::InnerIterator it(K.K_ff_lower, j); it; ++it)
      ASSERT_GE(it.row(), it.col());
  }
  EXPECT_EQ(K.K_fp.cols(), 0);
  EXPECT_EQ(K.K_pp.rows(), 0);
}

// Translations and infinitesimal rotations strain nothing: K r = 0, to round-off (1e-10 of |K| |r|).
TEST(AssembleStiffness, RigidBodyMotionsAreInTheNullSpace) {
  const TetMesh mesh = Box(3, 2, 2, Eigen::Vector3d(30, 20, 20));
  const Eigen::MatrixXd K =
      FromLower(AssembleStiffness(mesh, kMaterials, DofPartition(mesh.num_nodes(), {})).K_ff_lower);
  const double norm = K.norm();
  for (int mode = 0; mode < 6; ++mode) {
    Eigen::VectorXd r(3 * mesh.num_nodes());
    for (Eigen::Index i = 0; i < mesh.num_nodes(); ++i) {
      const Eigen::Vector3d x = mesh.nodes.row(i).transpose();
      const Eigen::Vector3d u =
          mode < 3 ? Eigen::Vector3d::Unit(mode) : Eigen::Vector3d::Unit(mode - 3).cross(x);
      r.segment<3>(3 * i) = u;
    }
    EXPECT_LT((K * r).norm(), 1e-10 * norm * r.norm()) << "mode " << mode;
  }
  // And nothing else is: exactly six zero eigenvalues.
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(K);
  const Eigen::VectorXd ev = eig.eigenvalues();
  EXPECT_LT(std::abs(ev(5)), 1e-10 * ev(ev.size() - 1));
  EXPECT_GT(ev(6), 1e-8 * ev(ev.size() - 1));
}

TEST(AssembleStiffness, PartitionedBlocksAreTheDenseBlocks) {
  const TetMesh mesh = Box(2, 1, 1, Eigen::Vector3d(20, 10, 10));
  std::vector<std::int32_t> fixed;
  for (Eigen::Index i = 0; i < mesh.num_nodes(); ++i) {
    if (mesh.nodes(i, 0) < 1e-9) fixed.push_back(static_cast<std::int32_t>(i));
  }
  const DofPartition p(mesh.num_nodes(), AllDofsOf(fixed));
  ASSERT_EQ(p.prescribed.size(), 3 * fixed.size());
  ASSERT_EQ(p.free.size() + p.prescribed.size(), static_cast<std::size_t>(3 * mesh.num_nodes()));
  const AssembledStiffness K = AssembleStiffness(mesh, kMaterials, p);
  const Eigen::MatrixXd dense = DenseStiffness(mesh, kMaterials);
  const double tolerance = 1e-12 * dense.cwiseAbs().maxCoeff();
  const Eigen::MatrixXd ff = FromLower(K.K_ff_lower), fp = Eigen::MatrixXd(K.K_fp),
                        pp = Eigen::MatrixXd(K.K_pp);
  for (std::size_t i = 0; i < p.free.size(); ++i) {
    for (std::size_t j = 0; j < p.free.size(); ++j)
      ASSERT_NEAR(ff(i, j), dense(p.free[i], p.free[j]), tolerance);
    for (std::size_t j = 0; j < p.prescribed.size(); ++j)
      ASSERT_NEAR(fp(i, j), dense(p.free[i], p.prescribed[j]), tolerance);
  }
  for (std::size_t i = 0; i < p.prescribed.size(); ++i) {
    for (std::size_t j = 0; j < p.prescribed.size(); ++j)
      ASSERT_NEAR(pp(i, j), dense(p.prescribed[i], p.prescribed[j]), tolerance);
  }
}

// A bar along x, stretched by delta: u_x = 0 on x = 0 and delta on x = L, each side plane y = 0 and
// z = 0 held only normal to itself (free to contract). Uniaxial stress: u = (delta x / L, -nu delta y
// / L, -nu delta z / L), which quadratic elements hold exactly (1e-9 mm for round-off), and the end
// force is E A delta / L (1e-9 relative).
TEST(AssembleStiffness, UniaxialBarMatchesTheClosedForm) {
  const double L = 40.0, b = 10.0, h = 8.0, delta = 0.05;
  const TetMesh mesh = Box(4, 2, 2, Eigen::Vector3d(L, b, h));
  const IsotropicMaterial m{"bar", 2000.0, 0.3};
  const std::vector<IsotropicMaterial> one = {m, m};
  std::vector<std::int32_t> prescribed;
  for (Eigen::Index i = 0; i < mesh.num_nodes(); ++i) {
    const auto n = static_cast<std::int32_t>(i);
    if (mesh.nodes(i, 0) < 1e-9 || mesh.nodes(i, 0) > L - 1e-9) prescribed.push_back(Dof(n, 0));
    if (mesh.nodes(i, 1) < 1e-9) prescribed.push_back(Dof(n, 1));
    if (mesh.nodes(i, 2) < 1e-9) prescribed.push_back(Dof(n, 2));
  }
  const DofPartition p(mesh.num_nodes(), prescribed);
  const AssembledStiffness K = AssembleStiffness(mesh, one, p);
  Eigen::VectorXd u_p(static_cast<Eigen::Index>(p.prescribed.size()));
  for (std::size_t k = 0; k < p.prescribed.size(); ++k) {
    const std::int32_t d = p.prescribed[k];
    u_p(static_cast<Eigen::Index>(k)) = d % 3 == 0 && mesh.nodes(d / 3, 0) > L / 2 ? delta : 0.0;
  }
  // K_ff u_f = -K_fp u_p, solved with Eigen's LDL^T (not the planner's CHOLMOD wrapper).
  const Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>, Eigen::Lower> ldlt(K.K_ff_lower);
  ASSERT_EQ(ldlt.info(), Eigen::Success);
  const Eigen::VectorXd u_f = ldlt.solve(Eigen::VectorXd(-(K.K_fp * u_p)));
  const double strain = delta / L;
  double worst = 0;
  for (std::size_t k = 0; k < p.free.size(); ++k) {
    const std::int32_t d = p.free[k];
    const Eigen::Vector3d x = mesh.nodes.row(d / 3).transpose();
    const double expected = d % 3 == 0 ? strain * x.x() : -m.poisson_ratio * strain * x(d % 3);
    worst = std::max(worst, std::abs(u_f(static_cast<Eigen::Index>(k)) - expected));
  }
  EXPECT_LT(worst, 1e-9) << "largest error, mm";
  // Reactions r_p = K_pf u_f + K_pp u_p: the x reactions on the far end sum to E A delta / L.
  const Eigen::VectorXd r = Eigen::SparseMatrix<double>(K.K_fp.transpose()) * u_f + K.K_pp * u_p;
  double pull = 0;
  for (std::size_t k = 0; k < p.prescribed.size(); ++k) {
    const std::int32_t d = p.prescribed[k];
    if (d % 3 == 0 && mesh.nodes(d / 3, 0) > L / 2) pull += r(static_cast<Eigen::Index>(k));
  }
  EXPECT_NEAR(pull, m.youngs_modulus_mpa * b * h * strain, 1e-9 * m.youngs_modulus_mpa * b * h * strain);
}

TEST(AssembleStiffness, BadInputIsNamed) {
  const TetMesh mesh = Box(2, 1, 1, Eigen::Vector3d(20, 10, 10));  // both regions
  const DofPartition p(mesh.num_nodes(), {});
  // A region without a material, an invalid material, a partition of another mesh.
  EXPECT_THROW(AssembleStiffness(mesh, {kMaterials[0]}, p), Error);
  EXPECT_THROW(AssembleStiffness(mesh, {kMaterials[0], IsotropicMaterial{"bad", 10.0, 0.5}}, p), Error);
  EXPECT_THROW(AssembleStiffness(mesh, kMaterials, DofPartition(mesh.num_nodes() + 1, {})), Error);
  EXPECT_THROW(DofPartition(mesh.num_nodes(), {-1}), Error);
  EXPECT_THROW(DofPartition(mesh.num_nodes(), {static_cast<std::int32_t>(3 * mesh.num_nodes())}), Error);
  // An inverted element is named: corners 1 and 2 swapped, with their edges' mid-nodes (0-1 with 2-0,
  // 1-3 with 2-3).
  TetMesh inverted = mesh;
  std::swap(inverted.tets(0, 1), inverted.tets(0, 2));
  std::swap(inverted.tets(0, 4), inverted.tets(0, 6));
  std::swap(inverted.tets(0, 8), inverted.tets(0, 9));
  try {
    AssembleStiffness(inverted, kMaterials, p);
    ADD_FAILURE() << "an inverted tetrahedron was assembled";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("tetrahedron 0"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace pectus::planner
