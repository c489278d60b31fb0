// The CHOLMOD factorisation against a dense LDL^T solve of the same symmetric positive definite
// matrix, in both modes; a matrix that is not positive definite, and misuse, are errors.
#include "planner_plugin/fem/sparse_cholesky.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <random>
#include <vector>

#include "shape/core/error.h"

namespace pectus::planner {
namespace {

// The 2D five-point Laplacian on an n x n grid with Dirichlet borders (SPD, condition ~ n^2), plus a
// random symmetric coupling between far-apart unknowns kept diagonally dominant: fill-in for the
// ordering to deal with. `shift` is added to the diagonal.
Eigen::SparseMatrix<double> TestMatrix(int n, double shift) {
  const int size = n * n;
  std::vector<Eigen::Triplet<double>> t;
  std::mt19937 rng(3);
  std::uniform_int_distribution<int> pick(0, size - 1);
  std::uniform_real_distribution<double> value(-0.5, 0.5);
  Eigen::VectorXd diagonal = Eigen::VectorXd::Constant(size, 4.0 + shift);
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      const int k = i * n + j;
      if (i + 1 < n) t.emplace_back(k + n, k, -1.0);
      if (j + 1 < n) t.emplace_back(k + 1, k, -1.0);
    }
  }
  for (int e = 0; e < size; ++e) {
    const int a = pick(rng), b = pick(rng);
    if (a == b) continue;
    const double v = value(rng);
    t.emplace_back(std::max(a, b), std::min(a, b), v);
    diagonal(a) += std::abs(v);
    diagonal(b) += std::abs(v);
  }
  for (int k = 0; k < size; ++k) t.emplace_back(k, k, diagonal(k));
  Eigen::SparseMatrix<double> lower(size, size);
  lower.setFromTriplets(t.begin(), t.end());  // duplicates are summed
  return lower;
}

Eigen::MatrixXd Full(const Eigen::SparseMatrix<double>& lower) {
  const Eigen::SparseMatrix<double> full = lower.selfadjointView<Eigen::Lower>();
  return Eigen::MatrixXd(full);
}

// Both are backward stable and the matrix is well conditioned (~100): the solutions agree to 1e-12
// relative.
TEST(SparseCholesky, SolvesLikeADenseLdltInBothModes) {
  const Eigen::SparseMatrix<double> A = TestMatrix(12, 0.0);
  const Eigen::MatrixXd dense = Full(A);
  const Eigen::MatrixXd B = Eigen::MatrixXd::Random(A.rows(), 3);
  const Eigen::MatrixXd expected = dense.ldlt().solve(B);
  for (const bool supernodal : {true, false}) {
    SparseCholesky cholesky(SparseCholeskyOptions{supernodal});
    cholesky.Factorize(A);
    const Eigen::MatrixXd X = cholesky.Solve(B);
    EXPECT_LT((X - expected).norm(), 1e-12 * expected.norm()) << (supernodal ? "supernodal" : "simplicial");
    EXPECT_LT((dense * X - B).norm(), 1e-12 * B.norm());
    // What it reports: the matrix's order and stored entries, the factor at least as full as A.
    const SparseCholeskySummary& s = cholesky.summary();
    EXPECT_EQ(s.rows, A.rows());
    EXPECT_EQ(s.nonzeros_lower, A.nonZeros());
    EXPECT_GE(s.nonzeros_factor, static_cast<double>(A.nonZeros()));
    EXPECT_GT(s.flops, 0.0);
    EXPECT_EQ(s.method, supernodal ? "CHOLMOD supernodal" : "CHOLMOD simplicial");
    EXPECT_EQ(cholesky.factorizations(), 1);
    EXPECT_EQ(cholesky.solved_columns(), 3);
  }
}

TEST(SparseCholesky, RefactorisingReplacesTheMatrix) {
  SparseCholesky cholesky;
  cholesky.Factorize(TestMatrix(8, 0.0));
  const Eigen::SparseMatrix<double> A = TestMatrix(8, 2.0);
  cholesky.Factorize(A);
  const Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(A.rows(), -1.0, 1.0);
  EXPECT_LT((Full(A) * cholesky.Solve(b) - b).norm(), 1e-12 * b.norm());
  EXPECT_EQ(cholesky.factorizations(), 2);
}

TEST(SparseCholesky, NotPositiveDefiniteIsAnError) {
  // The Laplacian shifted by -8 has negative eigenvalues (its spectrum lies in (0, 8) before the shift).
  SparseCholesky cholesky;
  try {
    cholesky.Factorize(TestMatrix(6, -8.0));
    ADD_FAILURE() << "an indefinite matrix was factorised";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("not positive definite"), std::string::npos) << e.what();
  }
}

TEST(SparseCholesky, MisuseIsAnError) {
  SparseCholesky cholesky;
  EXPECT_THROW(cholesky.Solve(Eigen::MatrixXd::Ones(4, 1)), Error);  // nothing factorised
  EXPECT_THROW(cholesky.Factorize(Eigen::SparseMatrix<double>(3, 4)), Error);
  EXPECT_THROW(cholesky.Factorize(Eigen::SparseMatrix<double>(0, 0)), Error);
  cholesky.Factorize(TestMatrix(4, 0.0));
  EXPECT_THROW(cholesky.Solve(Eigen::MatrixXd::Ones(15, 1)), Error);  // 16 rows expected
}

}  // namespace
}  // namespace pectus::planner
