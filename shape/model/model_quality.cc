#include "shape/model/model_quality.h"

#include <algorithm>
#include <cmath>
#include <exception>
#include <limits>
#include <random>

#include "shape/core/error.h"

namespace pectus {

bool ModelQualityOptions::IsValid(std::string* why) const {
  if (max_modes < 0 || specificity_samples < 1) {
    if (why != nullptr) *why = "quality curves need max modes >= 0 and at least 1 specificity sample";
    return false;
  }
  return model.IsValid(why);
}

double MeanVertexDistance(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  const Eigen::VectorXd d = VertexDistances(a, b);
  return d.size() > 0 ? d.mean() : 0.0;
}

void Generalization(const Eigen::MatrixXd& shapes, int max_modes, const ShapeModelOptions& options,
                    Eigen::VectorXd* mean_mm, Eigen::VectorXd* sd_mm) {
  const Eigen::Index n = shapes.rows();
  Eigen::MatrixXd errors = Eigen::MatrixXd::Zero(n, max_modes + 1);  // subject by M
  std::exception_ptr failure;
  // Leave-one-out models are independent: one per thread.
#pragma omp parallel for schedule(dynamic)
  for (Eigen::Index left = 0; left < n; ++left) {
    try {
      Eigen::MatrixXd others(n - 1, shapes.cols());
      for (Eigen::Index r = 0, o = 0; r < n; ++r) {
        if (r != left) others.row(o++) = shapes.row(r);
      }
      const ShapeModel model = BuildShapeModel(others, options, "leave-one-out shapes");
      const Eigen::VectorXd x = shapes.row(left).transpose();
      const Eigen::VectorXd alpha = model.basis.transpose() * (x - model.mean);
      Eigen::VectorXd reconstruction = model.mean;
      for (int m = 0; m <= max_modes; ++m) {
        if (m > 0 && m <= model.num_modes()) reconstruction += model.basis.col(m - 1) * alpha[m - 1];
        errors(left, m) = MeanVertexDistance(x, reconstruction);
      }
    } catch (...) {
#pragma omp critical(pectus_generalization)
      failure = std::current_exception();
    }
  }
  if (failure) std::rethrow_exception(failure);
  *mean_mm = errors.colwise().mean().transpose();
  sd_mm->resize(max_modes + 1);
  for (int m = 0; m <= max_modes; ++m) {
    const double var = (errors.col(m).array() - (*mean_mm)[m]).square().sum() / static_cast<double>(n - 1);
    (*sd_mm)[m] = std::sqrt(var / static_cast<double>(n - 1));
  }
}

double Specificity(const ShapeModel& model, const Eigen::MatrixXd& shapes,
                   const Eigen::MatrixXd& coefficients_sd, int modes, double* sd_mm) {
  const Eigen::Index samples = coefficients_sd.rows();
  const int m = std::min({modes, model.num_modes(), static_cast<int>(coefficients_sd.cols())});
  Eigen::VectorXd nearest(samples);
#pragma omp parallel for schedule(dynamic)
  for (Eigen::Index j = 0; j < samples; ++j) {
    const Eigen::VectorXd y = model.Instance(coefficients_sd.row(j).head(m).transpose());
    double best = std::numeric_limits<double>::infinity();
    for (Eigen::Index r = 0; r < shapes.rows(); ++r)
      best = std::min(best, MeanVertexDistance(y, shapes.row(r).transpose()));
    nearest[j] = best;
  }
  const double mean = nearest.mean();
  if (sd_mm != nullptr) {
    *sd_mm = samples > 1 ? std::sqrt((nearest.array() - mean).square().sum() /
                                     static_cast<double>(samples - 1) / static_cast<double>(samples - 1))
                         : 0.0;
  }
  return mean;
}

ModelQualityCurves EvaluateModelQuality(const Eigen::MatrixXd& shapes, const ModelQualityOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) ThrowUsage(why);
  const Eigen::Index n = shapes.rows();
  if (n < 3) ThrowBadInput("shapes", "quality curves need at least 3 shapes; got " + std::to_string(n));
  const ShapeModel model = BuildShapeModel(shapes, options.model, "shapes");
  int max_modes = static_cast<int>(n - 2);
  if (options.max_modes > 0) max_modes = std::min(max_modes, options.max_modes);
  max_modes = std::min(max_modes, model.num_modes());

  ModelQualityCurves q;
  q.modes = Eigen::VectorXi::LinSpaced(max_modes + 1, 0, max_modes);
  // Compactness: cumulative variance of the full model, with Styner's standard error sqrt(2/N) C(M).
  q.compactness = Eigen::VectorXd::Zero(max_modes + 1);
  for (int m = 1; m <= max_modes; ++m) q.compactness[m] = q.compactness[m - 1] + model.variances[m - 1];
  q.compactness_sd = std::sqrt(2.0 / static_cast<double>(n)) * q.compactness;
  // Generalization: leave-one-out.
  Generalization(shapes, max_modes, options.model, &q.generalization_mm, &q.generalization_sd);
  // Specificity: the same standard normal draws for every M, so the curve is smooth in M.
  std::mt19937_64 rng(options.seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  Eigen::MatrixXd b(options.specificity_samples, std::max(1, model.num_modes()));
  for (Eigen::Index r = 0; r < b.rows(); ++r) {
    for (Eigen::Index c = 0; c < b.cols(); ++c) b(r, c) = normal(rng);
  }
  q.specificity_mm.resize(max_modes + 1);
  q.specificity_sd.resize(max_modes + 1);
  for (int m = 0; m <= max_modes; ++m)
    q.specificity_mm[m] = Specificity(model, shapes, b, m, &q.specificity_sd[m]);
  return q;
}

}  // namespace pectus
