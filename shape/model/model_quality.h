// pectus: shape model quality as Styner et al. (2003) define it, "Evaluation of 3D correspondence
// methods for model building", IPMI, LNCS 2732: compactness, generalization and specificity as functions
// of the number of modes M.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <string>

#include "shape/model/shape_model.h"

namespace pectus {

/// How the quality curves are computed.
struct ModelQualityOptions {
  int max_modes = 0;  ///< curves for M = 0..max_modes (0: up to N - 2, all a leave-one-out model has)
  int specificity_samples = 200;  ///< random shapes drawn from the model per M (>= 1)
  std::uint64_t seed = 20030720;  ///< random generator seed (the curves are reproducible)
  ShapeModelOptions model;        ///< how each (leave-one-out) model is built

  /// False, with the reason, for a value out of range.
  bool IsValid(std::string* why) const;
};

/// The three curves, one value per M = 0..max (index M). The distance between two shapes |a - b| is the
/// mean Euclidean distance between corresponding vertices, mm.
struct ModelQualityCurves {
  Eigen::VectorXi modes;              ///< M
  Eigen::VectorXd compactness;        ///< C(M) = sum_{c <= M} lambda_c, mm^2 (full model)
  Eigen::VectorXd compactness_sd;     ///< sigma_C(M) = sqrt(2 / N) C(M)
  Eigen::VectorXd generalization_mm;  ///< G(M) = mean_n |x_n - x_n'(M)|, x_n' from the model without n
  Eigen::VectorXd generalization_sd;  ///< standard deviation of the N terms / sqrt(N - 1)
  Eigen::VectorXd specificity_mm;     ///< S(M) = mean_j min_n |y_j(M) - x_n|, y_j random model shapes
  Eigen::VectorXd specificity_sd;     ///< standard deviation of the terms / sqrt(samples - 1)
};

/// Mean Euclidean distance between corresponding vertices of two shape vectors (3m numbers each), mm.
double MeanVertexDistance(const Eigen::VectorXd& a, const Eigen::VectorXd& b);

/// Generalization: for each training shape n, builds the model of the others and reconstructs x_n with
/// M modes; returns G(M) and its standard error for M = 0..max_modes (N by 3m shapes, rows).
void Generalization(const Eigen::MatrixXd& shapes, int max_modes, const ShapeModelOptions& options,
                    Eigen::VectorXd* mean_mm, Eigen::VectorXd* sd_mm);

/// Specificity for given model shapes: S = mean over the rows b_j of `coefficients_sd` (samples by k,
/// standard deviations; columns beyond M are ignored) of the distance from model.Instance(b_j[0..M)) to the
/// nearest training shape (rows of `shapes`). Returns the mean and sets `sd_mm` to the standard error.
double Specificity(const ShapeModel& model, const Eigen::MatrixXd& shapes,
                   const Eigen::MatrixXd& coefficients_sd, int modes, double* sd_mm = nullptr);

/// All three curves for the shapes (N by 3m rows, N >= 3). Throws Error(kBadInput) for fewer than 3
/// shapes, Error(kUsage) for invalid options.
ModelQualityCurves EvaluateModelQuality(const Eigen::MatrixXd& shapes,
                                        const ModelQualityOptions& options = {});

}  // namespace pectus
