// pectus planner: sparse Cholesky factorisation (CHOLMOD, SuiteSparse), factorised once, solved many
// times. CHOLMOD stays behind this header.
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <memory>
#include <string>

#include "shape/core/timings.h"

namespace pectus::planner {

/// Options of the sparse Cholesky factorisation.
struct SparseCholeskyOptions {
  /// Supernodal (dense BLAS blocks) when true, simplicial (up-looking) when false. Default true.
  bool supernodal = true;
  bool IsValid(std::string* why) const;
};

/// What a factorisation cost.
struct SparseCholeskySummary {
  Eigen::Index rows = 0;            ///< order of the matrix
  Eigen::Index nonzeros_lower = 0;  ///< stored nonzeros of the lower triangle of A
  double nonzeros_factor = 0.0;     ///< nonzeros of L (CHOLMOD's estimate after analysis)
  double flops = 0.0;               ///< floating-point operations of the factorisation
  /// Wall time, s: "analyse" (fill-reducing ordering and symbolic analysis), "factorize" (numerical
  /// factorisation); of the last Factorize.
  Timings timings_s;
  std::string method;  ///< "CHOLMOD supernodal" or "CHOLMOD simplicial"
};

/// A = L L^T of a symmetric positive definite sparse matrix given by its lower triangle. Factorise
/// once, then Solve any number of right-hand sides (all columns of B at once).
class SparseCholesky {
 public:
  explicit SparseCholesky(const SparseCholeskyOptions& options = {});
  ~SparseCholesky();
  SparseCholesky(const SparseCholesky&) = delete;
  SparseCholesky& operator=(const SparseCholesky&) = delete;

  /// Orders, analyses and factorises A (lower triangle, #n by #n). Throws Error(kFailure) if A is not
  /// positive definite (e.g. an unconstrained rigid-body motion) naming the column at fault.
  void Factorize(const Eigen::SparseMatrix<double>& A_lower);
  /// X = A^{-1} B for #n by #cases B. Throws Error(kFailure) if nothing is factorised or sizes differ.
  Eigen::MatrixXd Solve(const Eigen::MatrixXd& B) const;

  /// How many times Factorize has run on this object.
  int factorizations() const { return factorizations_; }
  /// How many right-hand sides Solve has handled in total.
  Eigen::Index solved_columns() const { return solved_columns_; }
  const SparseCholeskySummary& summary() const { return summary_; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  SparseCholeskySummary summary_;
  int factorizations_ = 0;
  mutable Eigen::Index solved_columns_ = 0;
};

}  // namespace pectus::planner
