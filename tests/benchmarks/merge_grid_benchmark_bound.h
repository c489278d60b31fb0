// merge_grid_benchmark: the least shape error any merge of a scan's sweeps can reach on average (a
// Bayesian Cramér-Rao bound), to say how much of the error a merge leaves is in the data.
#pragma once

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <vector>

#include "datasets/chest_surface.h"
#include "datasets/scan_simulator.h"
#include "registration/kdtree.h"

namespace pectus::merge_grid {

/// The bound and what it rests on.
struct ShapeBound {
  double shape_rms_mm = 0.0;           ///< the least expected shape RMS after a rigid fit (mm)
  double noise_along_normal_mm = 0.0;  ///< the range noise along the normal, RMS over every inlier (mm)
  double overlap_points = 0.0;         ///< points of a sweep that another sweep covers, counted per pair
  double model_shape_rms_mm = 0.0;     ///< the same figure from the merge's own information (if given)
  /// The same bound over only the points the merge pairs at the truth (if given): what its coverage of
  /// the overlaps allows an efficient estimator, apart from how it weighs them.
  double paired_shape_rms_mm = 0.0;
  /// The chance that an efficient merge's shape RMS on this scan is at most the line's 0.06 mm: its pose
  /// errors drawn from the bound's posterior (ShapeRmsLaw), and from the paired bound's (if given). The
  /// bound is an expected RMS; one scan's RMS scatters about it, since a few pose errors carry it. 1
  /// where the bound is 0 (no tracker error, or one sweep); the paired chance is NaN when not computed.
  double p_within_line = 1.0, paired_p_within_line = std::numeric_limits<double>::quiet_NaN();
  /// Per sweep, the largest fraction of its true inliers that one other sweep covers (a true point of it
  /// within 2 mm): the overlap the sweep really has, against which a merge's linking is judged.
  std::vector<double> largest_overlap_fraction;
};

/// A point of sweep `source` (its row) that a merge pairs with sweep `target`.
struct PairedPoint {
  std::size_t source = 0, target = 0;
  std::uint32_t row = 0;
};

/// The shape RMS after a rigid fit (in the metric of the error along each point's normal) of sweeps whose
/// pose errors, twists (w, t) about their centres, are drawn from N(0, Sigma) (6n x 6n), over every 7th
/// point: its expected value sqrt(trace(A' P A Sigma) / N), and the chance that it is at most `line_mm`.
/// The squared RMS is e' A'PA e / N, a sum of lambda_i z_i^2 over the eigenvalues lambda_i of
/// L' A'PA L / N (Sigma = L L') with z_i independent standard normals; its law is drawn `draws` times
/// (seeded: the same figure every run; its standard error is at most 0.5 / sqrt(draws)).
struct ShapeRmsLaw {
  double expected_rms_mm = 0.0;
  double p_within_line = 0.0;
};
inline ShapeRmsLaw ShapeRmsDistribution(const std::vector<Points3>& points,
                                        const std::vector<Points3>& normals,
                                        const std::vector<Eigen::Vector3d>& centre,
                                        const Eigen::MatrixXd& Sigma, double line_mm = 0.06,
                                        int draws = 20000) {
  using Mat = Eigen::MatrixXd;
  using Vec6 = Eigen::Matrix<double, 6, 1>;
  const std::size_t n = points.size();
  Eigen::Vector3d c0 = Eigen::Vector3d::Zero();
  double total = 0.0;
  for (std::size_t s = 0; s < n; ++s)
    c0 += centre[s] * double(points[s].rows()), total += double(points[s].rows());
  c0 /= std::max(1.0, total);
  Mat AtA = Mat::Zero(Sigma.rows(), Sigma.cols()), BtA = Mat::Zero(6, Sigma.cols());
  Eigen::Matrix<double, 6, 6> BtB = Eigen::Matrix<double, 6, 6>::Zero();
  double count = 0.0;
  for (std::size_t s = 0; s < n; ++s) {
    const Eigen::Index a = 6 * Eigen::Index(s);
    Eigen::Matrix<double, 6, 6> AtA_s = Eigen::Matrix<double, 6, 6>::Zero(), BtA_s = AtA_s;
    for (Eigen::Index i = 0; i < points[s].rows(); i += 7) {
      const Eigen::Vector3d p = points[s].row(i).transpose(), nrm = normals[s].row(i).transpose();
      Vec6 ai, bi;
      ai << (p - centre[s]).cross(nrm), nrm;
      bi << (p - c0).cross(nrm), nrm;
      AtA_s += ai * ai.transpose();
      BtA_s += bi * ai.transpose();
      BtB += bi * bi.transpose();
      count += 1.0;
    }
    AtA.block(a, a, 6, 6) = AtA_s;
    BtA.block(0, a, 6, 6) = BtA_s;
  }
  const Mat AtPA = AtA - BtA.transpose() * BtB.ldlt().solve(BtA);
  ShapeRmsLaw law;
  law.expected_rms_mm = std::sqrt(std::max(0.0, (AtPA * Sigma).trace() / std::max(1.0, count)));
  const Eigen::LLT<Mat> llt(Sigma);
  if (llt.info() != Eigen::Success || draws < 1) return law;
  const Mat L = llt.matrixL();
  const Mat K = L.transpose() * AtPA * L / std::max(1.0, count);
  const Eigen::VectorXd lambda = Eigen::SelfAdjointEigenSolver<Mat>(0.5 * (K + K.transpose())).eigenvalues();
  std::mt19937_64 rng(13);
  std::normal_distribution<double> z;
  int within = 0;
  for (int d = 0; d < draws; ++d) {
    double r2 = 0.0;
    for (Eigen::Index i = 0; i < lambda.size(); ++i) {
      const double zi = z(rng);
      r2 += std::max(0.0, lambda(i)) * zi * zi;
    }
    within += r2 <= line_mm * line_mm;
  }
  law.p_within_line = double(within) / double(draws);
  return law;
}

/// The expected shape RMS of ShapeRmsDistribution alone.
inline double ExpectedShapeRms(const std::vector<Points3>& points, const std::vector<Points3>& normals,
                               const std::vector<Eigen::Vector3d>& centre, const Eigen::MatrixXd& Sigma) {
  return ShapeRmsDistribution(points, normals, centre, Sigma, 0.06, 0).expected_rms_mm;
}

/// The Bayesian Cramér-Rao bound of the issue-13 shape figure (merge_grid_benchmark_metrics.h,
/// Figures::shape_rms_mm) for one scan, at its truth.
///
/// Unknowns: every sweep's small pose error, a twist (w, t) about its true centroid c_s (a true point x
/// moves to x + w x (x - c_s) + t). What the data say (Fisher information): every true inlier p of sweep
/// s that sweep t covers (a true point of t within 2 mm) is one point-to-plane residual
/// n.(dx_s(p) - dx_t(p)) with the exact normal n; counted from both sweeps of the pair, each with
/// variance 2 (sigma_s^2 + sigma_t^2), so that a region of the overlap with point density rho on both
/// sides carries rho / (2 sigma^2) per unit area: each sweep's surface there is known to its own points'
/// noise, and the pair's offset to the sum of both (the surface is a nuisance, estimated locally, as
/// every overlap-based merge does). sigma_s is sweep s's range noise along the normal, measured from the
/// truth (the noisy point's offset from its noise-free hit, along the exact normal), so that grazing rays
/// count as the less noisy they are along the normal. What the tracker says (the prior): each sweep's
/// error as drawn by the generator, a rotation about the sweep's pivot (SweepTruth::pivot) and a
/// translation, isotropic Gaussians with the drawn magnitudes' second moments (SweepTruth::
/// rotation_error_deg, translation_error_mm). The posterior covariance Sigma = (F + prior)^-1 puts on every
/// 7th true inlier (as the figure samples them) an error along its normal; the common rigid motion is
/// fitted out in that metric (the least a rigid fit can leave, so the bound stays below the figure's 3D
/// fit); the bound is the expected RMS of what is left, sqrt(trace(A' P A Sigma) / N).
/// With `model_information` (a merge's joint normal matrix at the true poses, twists about the scan
/// frame's origin, AdjustPosesToTracker), the same figure from its inverse: what the merge's own model of
/// the data says it can reach (ShapeBound::model_shape_rms_mm).
/// A scan without tracker error (magnitudes 0) has bound 0. The bound is for any merge that aligns the
/// sweeps by their overlaps; it does not count a smoothness prior on the surface across sweeps.
inline ShapeBound BoundShapeError(const datasets::ChestSurface& surface,
                                  const std::vector<datasets::Sweep>& sweeps,
                                  const Eigen::MatrixXd* model_information = nullptr,
                                  const std::vector<PairedPoint>* paired = nullptr) {
  using Mat = Eigen::MatrixXd;
  ShapeBound out;
  const std::size_t n = sweeps.size();
  bool any_error = false;
  for (const auto& s : sweeps)
    any_error = any_error || s.truth.rotation_error_deg > 0.0 || s.truth.translation_error_mm > 0.0;

  // Each sweep's true inliers (scan frame), their exact normals, its centroid and its noise along them.
  std::vector<Points3> points(n), normals(n);
  std::vector<Eigen::Vector3d> centre(n);
  std::vector<double> sigma2(n);
  double noise_sum = 0.0, noise_count = 0.0;
  for (std::size_t s = 0; s < n; ++s) {
    const datasets::SweepTruth& t = sweeps[s].truth;
    std::vector<Eigen::Index> keep;
    for (Eigen::Index i = 0; i < t.true_points.rows(); ++i)
      if (!t.outlier[static_cast<std::size_t>(i)]) keep.push_back(i);
    points[s].resize(static_cast<Eigen::Index>(keep.size()), 3);
    normals[s].resize(static_cast<Eigen::Index>(keep.size()), 3);
    double e2 = 0.0;
    for (std::size_t k = 0; k < keep.size(); ++k) {
      const Eigen::Index i = keep[k];
      const Eigen::Vector3d x = t.true_points.row(i).transpose();
      const Eigen::Vector3d nrm = surface.Evaluate(t.u(i), t.v(i)).normal.normalized();
      points[s].row(static_cast<Eigen::Index>(k)) = x.transpose();
      normals[s].row(static_cast<Eigen::Index>(k)) = nrm.transpose();
      const Eigen::Vector3d measured =
          t.T_scan_sweep * Eigen::Vector3d(sweeps[s].cloud.positions.row(i).transpose());
      e2 += std::pow(nrm.dot(measured - x), 2);
    }
    sigma2[s] = keep.empty() ? 1.0 : std::max(1e-12, e2 / double(keep.size()));
    noise_sum += e2;
    noise_count += double(keep.size());
    centre[s] =
        points[s].rows() ? Eigen::Vector3d(points[s].colwise().mean().transpose()) : Eigen::Vector3d::Zero();
  }
  out.noise_along_normal_mm = std::sqrt(noise_sum / std::max(1.0, noise_count));
  out.largest_overlap_fraction.assign(n, 0.0);
  if (n < 2) return out;

  // The Fisher information of the overlaps.
  Mat F = Mat::Zero(6 * Eigen::Index(n), 6 * Eigen::Index(n));
  for (std::size_t t = 0; t < n; ++t) {
    if (points[t].rows() == 0) continue;
    const KdTree3 tree(points[t]);
    for (std::size_t s = 0; s < n; ++s) {
      if (s == t) continue;
      Mat block = Mat::Zero(12, 12);
      double covered = 0.0;
      for (Eigen::Index i = 0; i < points[s].rows(); ++i) {
        const Eigen::Vector3d p = points[s].row(i).transpose();
        std::uint32_t nearest = 0;
        double d2 = 0.0;
        if (!tree.Nearest(p, &nearest, &d2) || d2 > 4.0) continue;
        const Eigen::Vector3d nrm = normals[s].row(i).transpose();
        Eigen::Matrix<double, 12, 1> J;
        J << (p - centre[s]).cross(nrm), nrm, -(p - centre[t]).cross(nrm), -nrm;
        block += J * J.transpose();
        out.overlap_points += 1.0;
        covered += 1.0;
      }
      if (points[s].rows() > 0)
        out.largest_overlap_fraction[s] =
            std::max(out.largest_overlap_fraction[s], covered / double(points[s].rows()));
      block /= 2.0 * (sigma2[s] + sigma2[t]);
      const Eigen::Index a = 6 * Eigen::Index(s), b = 6 * Eigen::Index(t);
      F.block(a, a, 6, 6) += block.topLeftCorner(6, 6);
      F.block(a, b, 6, 6) += block.topRightCorner(6, 6);
      F.block(b, a, 6, 6) += block.bottomLeftCorner(6, 6);
      F.block(b, b, 6, 6) += block.bottomRightCorner(6, 6);
    }
  }

  if (!any_error) {
    if (paired) out.paired_p_within_line = 1.0;
    return out;
  }

  Mat F_paired;
  if (paired) {
    // The same information over the merge's own pairs: each paired point of a source sweep, its exact
    // normal, with the variance of the bound's count.
    F_paired = Mat::Zero(F.rows(), F.cols());
    std::vector<std::vector<Eigen::Index>> kept_row(n);  // cloud row -> inlier index
    for (std::size_t s = 0; s < n; ++s) {
      const datasets::SweepTruth& t = sweeps[s].truth;
      kept_row[s].assign(static_cast<std::size_t>(t.true_points.rows()), -1);
      Eigen::Index k = 0;
      for (Eigen::Index i = 0; i < t.true_points.rows(); ++i)
        if (!t.outlier[static_cast<std::size_t>(i)]) kept_row[s][static_cast<std::size_t>(i)] = k++;
    }
    for (const PairedPoint& pp : *paired) {
      const std::size_t s = pp.source, t = pp.target;
      if (s >= n || t >= n || pp.row >= kept_row[s].size() || kept_row[s][pp.row] < 0) continue;
      const Eigen::Vector3d p = points[s].row(kept_row[s][pp.row]).transpose();
      const Eigen::Vector3d nrm = normals[s].row(kept_row[s][pp.row]).transpose();
      Eigen::Matrix<double, 12, 1> J;
      J << (p - centre[s]).cross(nrm), nrm, -(p - centre[t]).cross(nrm), -nrm;
      const Eigen::Matrix<double, 12, 12> block = J * J.transpose() / (2.0 * (sigma2[s] + sigma2[t]));
      const Eigen::Index a = 6 * Eigen::Index(s), b = 6 * Eigen::Index(t);
      F_paired.block(a, a, 6, 6) += block.topLeftCorner(6, 6);
      F_paired.block(a, b, 6, 6) += block.topRightCorner(6, 6);
      F_paired.block(b, a, 6, 6) += block.bottomLeftCorner(6, 6);
      F_paired.block(b, b, 6, 6) += block.bottomRightCorner(6, 6);
    }
  }

  // The tracker's prior: (w, t_pivot) isotropic, moved to the twist about the centroid, t = t_pivot -
  // [c - pivot]x w.
  for (std::size_t s = 0; s < n; ++s) {
    const datasets::SweepTruth& t = sweeps[s].truth;
    const double var_w = std::max(1e-18, std::pow(t.rotation_error_deg * M_PI / 180.0, 2) / 3.0);
    const double var_t = std::max(1e-18, std::pow(t.translation_error_mm, 2) / 3.0);
    const Eigen::Vector3d a = centre[s] - t.pivot;
    Eigen::Matrix3d ax;
    ax << 0, -a.z(), a.y(), a.z(), 0, -a.x(), -a.y(), a.x(), 0;
    Eigen::Matrix<double, 6, 6> M = Eigen::Matrix<double, 6, 6>::Identity();
    M.block<3, 3>(3, 0) = -ax;
    Eigen::Matrix<double, 6, 6> D = Eigen::Matrix<double, 6, 6>::Zero();
    D.diagonal() << var_w, var_w, var_w, var_t, var_t, var_t;
    const Eigen::Matrix<double, 6, 6> C = M * D * M.transpose();
    F.block(6 * Eigen::Index(s), 6 * Eigen::Index(s), 6, 6) += C.inverse();
    if (paired) F_paired.block(6 * Eigen::Index(s), 6 * Eigen::Index(s), 6, 6) += C.inverse();
  }
  if (paired) {
    const ShapeRmsLaw law = ShapeRmsDistribution(
        points, normals, centre, F_paired.ldlt().solve(Mat::Identity(F_paired.rows(), F_paired.cols())));
    out.paired_shape_rms_mm = law.expected_rms_mm;
    out.paired_p_within_line = law.p_within_line;
  }
  const Mat Sigma = F.ldlt().solve(Mat::Identity(F.rows(), F.cols()));
  const ShapeRmsLaw law = ShapeRmsDistribution(points, normals, centre, Sigma);
  out.shape_rms_mm = law.expected_rms_mm;
  out.p_within_line = law.p_within_line;
  if (model_information) {
    // The merge's own model: its joint normal matrix at the true poses (twists about the scan origin),
    // as covariances of twists about the centres.
    const Mat& A = *model_information;
    Mat M = Mat::Identity(A.rows(), A.cols());
    for (std::size_t s = 0; s < n; ++s) {
      Eigen::Matrix3d cx;
      cx << 0, -centre[s].z(), centre[s].y(), centre[s].z(), 0, -centre[s].x(), -centre[s].y(), centre[s].x(),
          0;
      M.block(6 * Eigen::Index(s) + 3, 6 * Eigen::Index(s), 3, 3) = -cx;
    }
    const Mat Sigma_o = A.ldlt().solve(Mat::Identity(A.rows(), A.cols()));
    out.model_shape_rms_mm = ExpectedShapeRms(points, normals, centre, M * Sigma_o * M.transpose());
  }
  return out;
}

}  // namespace pectus::merge_grid
