#include "planner_plugin/fem/sparse_cholesky.h"

#include <Eigen/CholmodSupport>
#include <chrono>

#include "shape/core/error.h"

namespace pectus::planner {

struct SparseCholesky::Impl {
  Eigen::CholmodDecomposition<Eigen::SparseMatrix<double>, Eigen::Lower> solver;
};

bool SparseCholeskyOptions::IsValid(std::string* /*why*/) const { return true; }

SparseCholesky::SparseCholesky(const SparseCholeskyOptions& options) : impl_(std::make_unique<Impl>()) {
  impl_->solver.setMode(options.supernodal ? Eigen::CholmodSupernodalLLt : Eigen::CholmodSimplicialLLt);
  impl_->solver.cholmod().print = 0;  // failures are reported through Error, not printed
  summary_.method = options.supernodal ? "CHOLMOD supernodal" : "CHOLMOD simplicial";
}

SparseCholesky::~SparseCholesky() = default;

void SparseCholesky::Factorize(const Eigen::SparseMatrix<double>& A_lower) {
  if (A_lower.rows() != A_lower.cols() || A_lower.rows() == 0) {
    ThrowFailure("sparse Cholesky: the matrix must be square and non-empty, got " +
                 std::to_string(A_lower.rows()) + " by " + std::to_string(A_lower.cols()));
  }
  using Clock = std::chrono::steady_clock;
  auto& solver = impl_->solver;
  const auto t0 = Clock::now();
  solver.analyzePattern(A_lower);
  const auto t1 = Clock::now();
  if (solver.info() != Eigen::Success) ThrowFailure("sparse Cholesky: symbolic analysis failed (CHOLMOD)");
  solver.factorize(A_lower);
  const auto t2 = Clock::now();
  ++factorizations_;
  const cholmod_common& common = solver.cholmod();
  if (solver.info() != Eigen::Success) {
    ThrowFailure(
        "sparse Cholesky: the stiffness matrix is not positive definite (CHOLMOD status " +
        std::to_string(common.status) +
        "): is every part of the structure held by a boundary condition, and are all materials valid?");
  }
  summary_.rows = A_lower.rows();
  summary_.nonzeros_lower = A_lower.nonZeros();
  summary_.nonzeros_factor = common.lnz;
  summary_.flops = common.fl;
  summary_.timings_s = Timings();
  summary_.timings_s.Add("analyse", std::chrono::duration<double>(t1 - t0).count());
  summary_.timings_s.Add("factorize", std::chrono::duration<double>(t2 - t1).count());
}

Eigen::MatrixXd SparseCholesky::Solve(const Eigen::MatrixXd& B) const {
  if (factorizations_ == 0) ThrowFailure("sparse Cholesky: Solve called before Factorize");
  if (B.rows() != summary_.rows) {
    ThrowFailure("sparse Cholesky: right-hand side has " + std::to_string(B.rows()) + " rows, matrix has " +
                 std::to_string(summary_.rows));
  }
  Eigen::MatrixXd X = impl_->solver.solve(B);
  if (impl_->solver.info() != Eigen::Success) ThrowFailure("sparse Cholesky: solve failed (CHOLMOD)");
  solved_columns_ += B.cols();
  return X;
}

}  // namespace pectus::planner
