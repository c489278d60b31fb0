// pectus datasets: a population of normal chests from a few latent factors with known variances, and its
// exact mean shape and principal modes (docs/datasets.md, "Population").
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "datasets/chest_parameters.h"
#include "datasets/chest_surface.h"
#include "shape/core/geometry.h"

namespace pectus::datasets {

/// One latent factor: a standard normal variable b that moves the linear parameters by b * loading.
struct LatentFactor {
  std::string name;         ///< "size", "breadth", ...
  std::string description;  ///< what it changes, in words
  Eigen::VectorXd loading;  ///< kLinearParameterCount entries, mm per standard deviation
};

/// Linear parameters p = mean + sum_k b_k loading_k + detail, with b_k ~ N(0, 1) independent and each
/// detail coefficient ~ N(0, detail_sd_mm^2). Since the surface is affine in p, the population's mean
/// surface is exactly the surface of `mean`, and its covariance is exactly known.
struct PopulationModel {
  ChestParameters mean;  ///< no pectus, no growth, identity pose; detail empty (zero)
  std::vector<LatentFactor> factors;
  double detail_sd_mm = 1.4;  ///< standard deviation of each detail coefficient, mm

  /// The default adult population: six factors (size, breadth, height, adiposity, muscularity, costal).
  static PopulationModel Default();
  bool IsValid(std::string* why) const;
  /// A square root of the covariance of the linear parameters: kLinearParameterCount by (factors +
  /// kDetailCoefficients), covariance = A A^T. Column k < factors.size() is loading_k.
  Eigen::MatrixXd CovarianceRoot() const;
};

/// One subject drawn from a population.
struct SubjectSample {
  ChestParameters parameters;  ///< mean + factors + detail
  Eigen::VectorXd latent;      ///< the factors' values b_k (standard normal)
};

/// Draws one subject; the same seed gives the same subject (std::mt19937_64, then N(0,1) draws for the
/// factors in order, then for the detail coefficients).
SubjectSample SampleSubject(const PopulationModel& population, std::uint64_t seed);

/// A regular grid of surface parameters on which shapes are compared (the dissertation uses 51 by 101).
struct ShapeGrid {
  int nu = 51;   ///< vertices across
  int nv = 101;  ///< vertices up
  double u0 = kUMin, u1 = kUMax, v0 = kVMin, v1 = kVMax;
  /// (u, v) of grid vertex k = j * nu + i.
  Eigen::Vector2d At(Eigen::Index k) const;
  Eigen::Index size() const { return static_cast<Eigen::Index>(nu) * nv; }
};

/// Skin positions of a surface at every grid vertex (#grid by 3, mm, scan frame).
Points3 SampleGrid(const ChestSurface& surface, const ShapeGrid& grid);

/// The population's exact shape statistics on a grid: shape vectors s = (x_1, y_1, z_1, ..., z_m) of the
/// skin at the grid vertices have mean `mean` and covariance sum_j eigenvalues_j modes_j modes_j^T.
struct TrueShapeStatistics {
  ShapeGrid grid;
  Points3 mean;                 ///< #grid by 3, mm
  Eigen::VectorXd eigenvalues;  ///< the first `count`, descending, mm^2
  Eigen::VectorXd explained;    ///< eigenvalue / total variance
  double total_variance = 0.0;  ///< trace of the covariance, mm^2
  std::vector<Points3> modes;   ///< #grid by 3 each; unit norm as 3m-vectors; largest entry positive
  /// kLinearParameterCount by count: the parameters of mode j, so that the surface of mean + t C(:, j)
  /// minus the mean surface is t * modes[j] at the grid (and a smooth function of (u, v) elsewhere).
  Eigen::MatrixXd mode_parameters;
};

/// Computes the exact mean and the first `count` principal modes of the population on `grid`.
TrueShapeStatistics ComputeTrueShapeStatistics(const PopulationModel& population, const ShapeGrid& grid,
                                               int count);

/// The parameters of the mean shape moved by `sd` standard deviations along true mode j:
/// mean + sd sqrt(eigenvalue_j) mode_parameters(:, j).
ChestParameters AlongMode(const PopulationModel& population, const TrueShapeStatistics& statistics, int j,
                          double sd);

/// JSON description of the population (mean, factors, detail) and of the statistics (grid, eigenvalues).
nlohmann::json PopulationJson(const PopulationModel& population, const TrueShapeStatistics& statistics);

}  // namespace pectus::datasets
