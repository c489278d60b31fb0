// pectus: the average chest and its principal modes (dissertation §4.3.1, Eqs. 13-14): PCA of the
// centred shape vectors by the N x N Gram matrix (N subjects << 3m numbers per shape).
#pragma once

#include <Eigen/Core>
#include <functional>
#include <string>
#include <vector>

#include "shape/core/geometry.h"

namespace pectus {

class TaskRunner;

/// How the model is built.
struct ShapeModelOptions {
  /// Keep at most this many modes (0: every mode with variance above `relative_tolerance`, at most N-1).
  int max_modes = 0;
  /// Modes whose variance is below this fraction of the largest are dropped as numerical zeros.
  double relative_tolerance = 1e-10;
  /// Isotropic noise variance written to the model (statismo's PPCA noise), mm^2, >= 0.
  double noise_variance = 0.0;

  /// False, with the reason, for a value out of range.
  bool IsValid(std::string* why) const;
};

/// A linear statistical shape model: x = mean + basis * alpha, alpha_i ~ N(0, variances_i).
struct ShapeModel {
  Eigen::VectorXd mean;            ///< 3m numbers (x1, y1, z1, ...), mm
  Eigen::MatrixXd basis;           ///< 3m by k, orthonormal columns (the eigenvectors e_c of Eq. 14)
  Eigen::VectorXd variances;       ///< k eigenvalues lambda = s^2 / (N - 1), descending, mm^2
  double total_variance = 0.0;     ///< trace of the sample covariance (all modes, kept or not), mm^2
  double noise_variance = 0.0;     ///< mm^2
  Eigen::MatrixXd scores;          ///< N by k: basis' (x_n - mean) of the training shapes, mm (Eq. 14's z_n)
  Faces3 faces;                    ///< triangles over the m vertices (empty for a point model)
  std::vector<std::string> names;  ///< N training subject names (may be empty)

  Eigen::Index num_points() const { return mean.size() / 3; }
  int num_modes() const { return static_cast<int>(variances.size()); }
  /// Fraction of the total variance explained by each mode (k values).
  Eigen::VectorXd ExplainedFraction() const;
  /// Cumulative ExplainedFraction (k values, the last <= 1).
  Eigen::VectorXd CumulativeFraction() const;
  /// The shape mean + sum_c b_c sqrt(lambda_c) e_c for coefficients `b` in standard deviations (size
  /// <= k; missing entries are 0). Throws Error(kUsage) for more than k coefficients.
  Eigen::VectorXd Instance(const Eigen::VectorXd& b_sd) const;
  /// A shape as a mesh with the model's faces.
  TriangleMesh ToMesh(const Eigen::VectorXd& shape) const;
  /// Throws Error(kBadInput) naming `what` if the sizes disagree or a number is not finite.
  void Validate(const std::string& what) const;
  /// One line: shapes, points, modes, and the variance the first and the first three modes explain.
  std::string BriefReport() const;
};

/// Builds the model of N shapes (rows of `shapes`, N by 3m, mm). N >= 2. The basis comes from the
/// eigenvectors V of the Gram matrix G = X X' of the centred data X (N by 3m): e = X' v / s,
/// lambda = s^2 / (N - 1), which equals the SVD of X and costs O(N^2 3m). Eigenvector signs are fixed
/// so that each basis vector's largest component is positive.
/// Throws Error(kBadInput) naming `what` for fewer than 2 shapes, a width not a multiple of 3, or a
/// non-finite number; Error(kUsage) for invalid options.
/// The eigen decomposition of the symmetric `G` (its lower half is read) by LAPACK's divide and conquer
/// (dsyevd): eigenvalues ascending in `values`, their unit eigenvectors the columns of `vectors`. False if
/// LAPACK reports a failure.
bool SymmetricEigen(const Eigen::MatrixXd& G, Eigen::VectorXd* values, Eigen::MatrixXd* vectors);

/// With a `runner` of several processes (MPI ranks: docs/cluster.md) it is a collective: every process
/// calls it with the same shapes; the Gram matrix, the basis and the scores are computed in blocks shared
/// among them, the eigen decomposition on the leader; every process's model is the bytes of a run on one
/// process.
/// `while_decomposing`, if given, runs on every process while the leader decomposes the Gram matrix in a
/// thread of its own (a collective of the caller's, e.g. the pipeline's per-subject tasks, which need only
/// the mean: the decomposition's time then hides in theirs); `decomposition_seconds`, if given, gets the
/// decomposition's wall time on the leader (0 elsewhere).
ShapeModel BuildShapeModel(const Eigen::MatrixXd& shapes, const ShapeModelOptions& options = {},
                           const std::string& what = "shapes", TaskRunner* runner = nullptr,
                           const std::function<void()>& while_decomposing = {},
                           double* decomposition_seconds = nullptr);

/// A shape expressed in the model.
struct ShapeProjection {
  Eigen::VectorXd scores;          ///< k coefficients alpha = basis' (x - mean), mm
  Eigen::VectorXd scores_sd;       ///< alpha_c / sqrt(lambda_c), standard deviations
  Eigen::VectorXd reconstruction;  ///< mean + basis alpha (3m numbers, mm)
  double rms_error_mm = 0.0;       ///< RMS of the per-vertex distances shape - reconstruction, mm
  double max_error_mm = 0.0;       ///< largest per-vertex distance, mm
  double mahalanobis = 0.0;        ///< sqrt(sum alpha_c^2 / lambda_c)
};

/// Projects a shape (3m numbers, mm) on the first `modes` modes (-1: all). Throws Error(kBadInput) for a
/// size that differs from the model's, Error(kUsage) for modes > k.
ShapeProjection ProjectShape(const ShapeModel& model, const Eigen::VectorXd& shape, int modes = -1);

/// Per-vertex Euclidean distances between two shape vectors of the same size (m values, mm).
Eigen::VectorXd VertexDistances(const Eigen::VectorXd& a, const Eigen::VectorXd& b);

}  // namespace pectus
