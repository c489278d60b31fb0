#include "shape/model/shape_model.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <future>
#include <vector>

#include "shape/core/error.h"
#include "shape/core/task_runner.h"
#include "shape/model/shape_grid.h"

// LAPACK: the eigenvalues (ascending) and eigenvectors of a symmetric matrix by divide and conquer.
extern "C" void dsyevd_(const char* jobz, const char* uplo, const int* n, double* a, const int* lda,
                        double* w, double* work, const int* lwork, int* iwork, const int* liwork, int* info);

namespace pectus {

bool SymmetricEigen(const Eigen::MatrixXd& G, Eigen::VectorXd* values, Eigen::MatrixXd* vectors) {
  const int n = static_cast<int>(G.rows());
  *vectors = G;
  values->resize(n);
  int lwork = -1, liwork = -1, info = 0, iwork_size = 0;
  double work_size = 0.0;
  dsyevd_("V", "L", &n, vectors->data(), &n, values->data(), &work_size, &lwork, &iwork_size, &liwork, &info);
  if (info != 0) return false;
  lwork = static_cast<int>(work_size);
  liwork = iwork_size;
  std::vector<double> work(static_cast<std::size_t>(std::max(1, lwork)));
  std::vector<int> iwork(static_cast<std::size_t>(std::max(1, liwork)));
  dsyevd_("V", "L", &n, vectors->data(), &n, values->data(), work.data(), &lwork, iwork.data(), &liwork,
          &info);
  return info == 0;
}

bool ShapeModelOptions::IsValid(std::string* why) const {
  auto fail = [&](const std::string& m) {
    if (why != nullptr) *why = m;
    return false;
  };
  if (max_modes < 0) return fail("the number of modes must be >= 0 (0: all)");
  if (!(relative_tolerance >= 0.0 && relative_tolerance < 1.0))
    return fail("relative tolerance must be in [0, 1)");
  if (!(noise_variance >= 0.0) || !std::isfinite(noise_variance))
    return fail("noise variance must be >= 0 mm^2");
  return true;
}

Eigen::VectorXd ShapeModel::ExplainedFraction() const {
  if (total_variance <= 0.0) return Eigen::VectorXd::Zero(variances.size());
  return variances / total_variance;
}

std::string ShapeModel::BriefReport() const {
  const Eigen::VectorXd cumulative = CumulativeFraction();
  const auto at = [&](int k) {
    return cumulative.size() > 0 ? 100.0 * cumulative(std::min<Eigen::Index>(k, cumulative.size()) - 1) : 0.0;
  };
  char line[300];
  std::snprintf(
      line, sizeof(line),
      "%lld shapes, %lld points, %d modes: the first explains %.1f %%, the first three %.1f %% of the "
      "total variance %.4g mm^2",
      static_cast<long long>(scores.rows()), static_cast<long long>(num_points()), num_modes(), at(1), at(3),
      total_variance);
  return line;
}

Eigen::VectorXd ShapeModel::CumulativeFraction() const {
  Eigen::VectorXd f = ExplainedFraction();
  for (Eigen::Index c = 1; c < f.size(); ++c) f[c] += f[c - 1];
  return f;
}

Eigen::VectorXd ShapeModel::Instance(const Eigen::VectorXd& b_sd) const {
  if (b_sd.size() > num_modes()) {
    ThrowUsage(std::to_string(b_sd.size()) + " mode coefficients given; the model has " +
               std::to_string(num_modes()) + " modes");
  }
  const Eigen::Index k = b_sd.size();
  return mean + basis.leftCols(k) * (b_sd.array() * variances.head(k).array().sqrt()).matrix();
}

TriangleMesh ShapeModel::ToMesh(const Eigen::VectorXd& shape) const {
  TriangleMesh mesh;
  mesh.vertices.positions = FromShapeVector(shape);
  mesh.faces = faces;
  return mesh;
}

void ShapeModel::Validate(const std::string& what) const {
  const Eigen::Index d = mean.size(), k = variances.size();
  if (d == 0 || d % 3 != 0) ThrowBadInput(what, "the mean has " + std::to_string(d) + " numbers, not 3m > 0");
  if (basis.rows() != d || basis.cols() != k) {
    ThrowBadInput(what, "the basis is " + std::to_string(basis.rows()) + " x " +
                            std::to_string(basis.cols()) + ", expected " + std::to_string(d) + " x " +
                            std::to_string(k));
  }
  if (scores.size() > 0 && scores.cols() != k) {
    ThrowBadInput(what, "the scores have " + std::to_string(scores.cols()) + " columns for " +
                            std::to_string(k) + " modes");
  }
  if (!names.empty() && scores.size() > 0 && static_cast<Eigen::Index>(names.size()) != scores.rows()) {
    ThrowBadInput(what,
                  std::to_string(names.size()) + " names for " + std::to_string(scores.rows()) + " subjects");
  }
  if (!mean.allFinite() || !basis.allFinite() || !variances.allFinite() || !scores.allFinite() ||
      !std::isfinite(noise_variance) || !std::isfinite(total_variance)) {
    ThrowBadInput(what, "the model holds a non-finite number");
  }
  if ((variances.array() < 0.0).any()) ThrowBadInput(what, "a mode has negative variance");
  if (faces.size() > 0 && (faces.minCoeff() < 0 || faces.maxCoeff() >= num_points())) {
    ThrowBadInput(what, "a face refers to a vertex beyond the " + std::to_string(num_points()) + " points");
  }
}

ShapeModel BuildShapeModel(const Eigen::MatrixXd& shapes, const ShapeModelOptions& options,
                           const std::string& what, TaskRunner* runner,
                           const std::function<void()>& while_decomposing, double* decomposition_seconds) {
  std::string why;
  if (!options.IsValid(&why)) ThrowUsage(why);
  const Eigen::Index n = shapes.rows(), d = shapes.cols();
  if (n < 2) ThrowBadInput(what, "a shape model needs at least 2 shapes; got " + std::to_string(n));
  if (d == 0 || d % 3 != 0)
    ThrowBadInput(what, "shape vectors have " + std::to_string(d) + " numbers, not 3m > 0");
  if (!shapes.allFinite()) ThrowBadInput(what, "a shape vector holds a non-finite number");

  SerialTaskRunner serial;
  TaskRunner& farm = runner != nullptr ? *runner : serial;
  ShapeModel model;
  model.noise_variance = options.noise_variance;
  // Mean shape (Eq. 14's a_sh) and centred data X (N by 3m).
  model.mean = shapes.colwise().mean().transpose();
  const Eigen::MatrixXd X = shapes.rowwise() - model.mean.transpose();

  // Gram matrix G = X X' (N by N): blocks of rows of its lower half (up to the block's diagonal), each a
  // product on one process, then mirrored.
  using RowMajor = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
  const Eigen::Index kRows = BlockRows(n, 32);
  RowMajor lower(n, n);
  farm.ComputeBlocks(
      BlockOffsets(n, kRows, n),
      [&](int b, double* out) {
        const Eigen::Index first = b * kRows, rows = std::min(kRows, n - first);
        Eigen::Map<RowMajor> block(out, rows, n);
        block.setZero();
        block.leftCols(first + rows).noalias() =
            X.middleRows(first, rows) * X.topRows(first + rows).transpose();
      },
      lower.data());
  Eigen::MatrixXd G = lower;
  G.triangularView<Eigen::StrictlyUpper>() = G.transpose();
  model.total_variance = std::max(0.0, G.trace()) / static_cast<double>(n - 1);

  // Its eigen decomposition G = V S^2 V' on the leader (descending), to every process.
  Eigen::VectorXd s2(n);
  Eigen::MatrixXd V(n, n);
  std::string failure;
  bool ok = true;
  if (decomposition_seconds != nullptr) *decomposition_seconds = 0.0;
  if (farm.IsLeader()) {
    Eigen::VectorXd values;
    Eigen::MatrixXd vectors;
    auto decompose = [&] {
      const auto start = std::chrono::steady_clock::now();
      const bool done = SymmetricEigen(G, &values, &vectors);
      if (decomposition_seconds != nullptr)
        *decomposition_seconds =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      return done;
    };
    if (while_decomposing) {
      std::future<bool> decomposed = std::async(std::launch::async, decompose);
      while_decomposing();  // if it throws, the future waits for the decomposition
      ok = decomposed.get();
    } else {
      ok = decompose();
    }
    if (ok) {
      s2 = values.reverse();
      V = vectors.rowwise().reverse();
    } else {
      failure = "the eigen decomposition of the Gram matrix failed for " + what;
    }
  } else if (while_decomposing) {
    while_decomposing();
  }
  if (!farm.BroadcastOutcome(ok, &failure)) ThrowFailure(failure);
  farm.Broadcast(s2.data(), n * static_cast<std::int64_t>(sizeof(double)));
  Eigen::Index k = 0;
  const double largest = std::max(s2[0], 0.0);
  while (k < n - 1 && s2[k] > options.relative_tolerance * largest && s2[k] > 0.0) ++k;
  if (options.max_modes > 0) k = std::min<Eigen::Index>(k, options.max_modes);
  farm.Broadcast(V.data(), n * k * static_cast<std::int64_t>(sizeof(double)));  // its first k columns

  // Eigenvectors of the covariance: e_c = X' v_c / s_c, in blocks of modes, on every process (each can
  // then write the files made of the model); eigenvalues lambda_c = s_c^2 / (N - 1).
  const Eigen::Index kModes = BlockRows(k, 64);
  model.basis.resize(d, k);
  farm.ComputeBlocks(
      BlockOffsets(k, kModes, d),
      [&](int b, double* out) {
        const Eigen::Index first = b * kModes, modes = std::min(kModes, k - first);
        Eigen::Map<Eigen::MatrixXd>(out, d, modes).noalias() = X.transpose() * V.middleCols(first, modes);
      },
      model.basis.data());
  model.variances.resize(k);
  // Scores of the training shapes (Eq. 14's z_n): basis' (x_n - mean) = G v_c / |X' v_c|, signed as e_c.
  Eigen::VectorXd factor(k);
  for (Eigen::Index c = 0; c < k; ++c) {
    model.variances[c] = s2[c] / static_cast<double>(n - 1);
    const double s = std::sqrt(s2[c]);
    model.basis.col(c) /= s;
    const double norm = model.basis.col(c).norm();
    model.basis.col(c).normalize();  // removes the rounding of 1 / s
    Eigen::Index largest_row;
    model.basis.col(c).cwiseAbs().maxCoeff(&largest_row);
    const double sign = model.basis(largest_row, c) < 0.0 ? -1.0 : 1.0;
    model.basis.col(c) *= sign;
    factor[c] = sign / (s * norm);
  }
  model.scores.resize(n, k);  // on every process: each subject's own record takes its scores
  farm.ComputeBlocks(
      BlockOffsets(k, kModes, n),
      [&](int b, double* out) {
        const Eigen::Index first = b * kModes, modes = std::min(kModes, k - first);
        Eigen::Map<Eigen::MatrixXd> block(out, n, modes);
        block.noalias() = G * V.middleCols(first, modes);
        block *= factor.segment(first, modes).asDiagonal();
      },
      model.scores.data());
  return model;
}

ShapeProjection ProjectShape(const ShapeModel& model, const Eigen::VectorXd& shape, int modes) {
  if (shape.size() != model.mean.size()) {
    ThrowBadInput("shape", "has " + std::to_string(shape.size()) + " numbers; the model's shapes have " +
                               std::to_string(model.mean.size()));
  }
  if (modes > model.num_modes()) {
    ThrowUsage(std::to_string(modes) + " modes asked; the model has " + std::to_string(model.num_modes()));
  }
  const Eigen::Index k = modes < 0 ? model.num_modes() : modes;
  ShapeProjection p;
  p.scores = model.basis.leftCols(k).transpose() * (shape - model.mean);
  p.scores_sd = p.scores.array() / model.variances.head(k).array().sqrt();
  p.reconstruction = model.mean + model.basis.leftCols(k) * p.scores;
  const Eigen::VectorXd e = VertexDistances(shape, p.reconstruction);
  p.rms_error_mm = std::sqrt(e.squaredNorm() / static_cast<double>(e.size()));
  p.max_error_mm = e.size() > 0 ? e.maxCoeff() : 0.0;
  p.mahalanobis = p.scores_sd.norm();
  return p;
}

Eigen::VectorXd VertexDistances(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  const Eigen::VectorXd diff = a - b;
  const Eigen::Map<const Points3> d(diff.data(), diff.size() / 3, 3);
  return d.rowwise().norm();
}

}  // namespace pectus
