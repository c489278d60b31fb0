#include "shape/surface/surface_normals.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

#include "registration/estimate_normals.h"
#include "shape/core/error.h"

namespace pectus {
namespace {

// Fraction of (up to 512 evenly picked) k-neighbourhoods that are lines: the middle eigenvalue of their
// covariance below 1e-4 of the largest, so that no plane and no normal is defined.
double LinearFraction(const Points3& points, const KdTree3& tree, int k) {
  const Eigen::Index n = points.rows();
  const Eigen::Index samples = std::min<Eigen::Index>(n, 512);
  int linear = 0;
#pragma omp parallel reduction(+ : linear)
  {
    std::vector<std::uint32_t> idx(static_cast<std::size_t>(k));
    std::vector<double> d2(static_cast<std::size_t>(k));
#pragma omp for schedule(static)
    for (Eigen::Index s = 0; s < samples; ++s) {
      const int found = tree.Knn(points.row(s * n / samples).transpose(), k, idx.data(), d2.data());
      Eigen::Vector3d mean = Eigen::Vector3d::Zero();
      for (int j = 0; j < found; ++j) mean += points.row(idx[std::size_t(j)]).transpose();
      mean /= double(std::max(1, found));
      Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
      for (int j = 0; j < found; ++j) {
        const Eigen::Vector3d d = points.row(idx[std::size_t(j)]).transpose() - mean;
        cov += d * d.transpose();
      }
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig;
      eig.computeDirect(cov, Eigen::EigenvaluesOnly);
      if (eig.eigenvalues()(1) <= 1e-4 * eig.eigenvalues()(2)) ++linear;
    }
  }
  return double(linear) / double(std::max<Eigen::Index>(1, samples));
}

}  // namespace

bool SurfaceNormalOptions::IsValid(std::string* why) const {
  if (neighbours < 3 || neighbours > 256) {
    if (why) *why = "normal neighbours must be in [3, 256]";
    return false;
  }
  if (viewpoint && !viewpoint->allFinite()) {
    if (why) *why = "viewpoint must be finite";
    return false;
  }
  return true;
}

SurfaceNormalResult SurfaceNormals(const PointCloud& cloud, const KdTree3& tree,
                                   const SurfaceNormalOptions& options, const std::string& what) {
  std::string why;
  if (!options.IsValid(&why)) ThrowUsage("normals: " + why);
  SurfaceNormalResult result;
  if (cloud.has_normals() && !options.recompute) {
    result.normals = cloud.normals;
    Eigen::Index bad = 0;
    for (Eigen::Index i = 0; i < result.normals.rows(); ++i) {
      const double len = result.normals.row(i).norm();
      if (len > 0.5 && std::isfinite(len)) {
        result.normals.row(i) /= len;
      } else {
        result.normals.row(i).setZero();
        ++bad;
      }
    }
    result.source = "input";
    if (bad > result.normals.rows() / 10) result.normals.resize(0, 3);  // mostly unusable: estimate instead
  }
  if (result.normals.rows() == 0) {
    const double linear = LinearFraction(cloud.positions, tree, options.neighbours);
    if (linear > 0.5) {
      ThrowBadInput(what,
                    "no normals obtainable: the " + std::to_string(options.neighbours) +
                        " nearest neighbours of " + std::to_string(int(std::lround(100.0 * linear))) +
                        " % of the points lie on a line (scan lines farther apart than the neighbourhood "
                        "reaches; raise --normal-neighbours or give normals)");
    }
    NormalOptions no;
    no.k = options.neighbours;
    no.propagation_k = std::min(8, no.k);
    no.orientation = options.viewpoint ? NormalOrientation::kTowardViewpoint : NormalOrientation::kPropagate;
    if (options.viewpoint) no.viewpoint = *options.viewpoint;
    result.normals = EstimateNormals(cloud.positions, no, &tree).normals;
    result.source = options.viewpoint ? "viewpoint" : "propagated";
  }
  for (Eigen::Index i = 0; i < result.normals.rows(); ++i)
    result.usable += result.normals.row(i).squaredNorm() > 0.25;
  if (result.usable < cloud.size() / 2) {
    ThrowBadInput(what, "no normals obtainable: only " + std::to_string(result.usable) + " of " +
                            std::to_string(cloud.size()) +
                            " points have a neighbourhood spread in two directions");
  }
  return result;
}

}  // namespace pectus
