#include "shape/model/shape_model.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdio>

#include "shape/core/error.h"
#include "shape/model/shape_grid.h"

namespace pectus {

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
                           const std::string& what) {
  std::string why;
  if (!options.IsValid(&why)) ThrowUsage(why);
  const Eigen::Index n = shapes.rows(), d = shapes.cols();
  if (n < 2) ThrowBadInput(what, "a shape model needs at least 2 shapes; got " + std::to_string(n));
  if (d == 0 || d % 3 != 0)
    ThrowBadInput(what, "shape vectors have " + std::to_string(d) + " numbers, not 3m > 0");
  if (!shapes.allFinite()) ThrowBadInput(what, "a shape vector holds a non-finite number");

  ShapeModel model;
  model.noise_variance = options.noise_variance;
  // Mean shape (Eq. 14's a_sh) and centred data X (N by 3m).
  model.mean = shapes.colwise().mean().transpose();
  const Eigen::MatrixXd X = shapes.rowwise() - model.mean.transpose();

  // Gram matrix G = X X' (N by N; its lower half, a symmetric rank-3m update at half the cost of the
  // product) and its eigen decomposition G = V S^2 V', which reads only the lower half.
  Eigen::MatrixXd G = Eigen::MatrixXd::Zero(n, n);
  G.selfadjointView<Eigen::Lower>().rankUpdate(X);
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(G);
  if (eig.info() != Eigen::Success)
    ThrowFailure("the eigen decomposition of the Gram matrix failed for " + what);
  // Eigenvalues ascending: reverse to descending.
  const Eigen::VectorXd s2 = eig.eigenvalues().reverse();
  const Eigen::MatrixXd V = eig.eigenvectors().rowwise().reverse();
  model.total_variance = std::max(0.0, G.trace()) / static_cast<double>(n - 1);

  Eigen::Index k = 0;
  const double largest = std::max(s2[0], 0.0);
  while (k < n - 1 && s2[k] > options.relative_tolerance * largest && s2[k] > 0.0) ++k;
  if (options.max_modes > 0) k = std::min<Eigen::Index>(k, options.max_modes);

  // Eigenvectors of the covariance: e_c = X' v_c / s_c; eigenvalues lambda_c = s_c^2 / (N - 1).
  model.basis.noalias() = X.transpose() * V.leftCols(k);
  model.variances.resize(k);
  for (Eigen::Index c = 0; c < k; ++c) {
    const double s = std::sqrt(s2[c]);
    model.basis.col(c) /= s;
    model.basis.col(c).normalize();  // removes the rounding of 1 / s
    model.variances[c] = s2[c] / static_cast<double>(n - 1);
    Eigen::Index largest_row;
    model.basis.col(c).cwiseAbs().maxCoeff(&largest_row);
    if (model.basis(largest_row, c) < 0.0) model.basis.col(c) *= -1.0;
  }
  // Scores of the training shapes (Eq. 14's z_n): basis' (x_n - mean).
  model.scores.noalias() = X * model.basis;
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
