// merge_grid_benchmark: how far merged sweeps lie from the truth, and how well their overlaps pin them.
#pragma once

#include <Eigen/Dense>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "datasets/chest_surface.h"
#include "datasets/scan_simulator.h"
#include "datasets/surface_query.h"
#include "registration/kdtree.h"
#include "registration/pose_error.h"

namespace pectus::merge_grid {

/// Figures of one merge against the truth, after the one rigid motion G that best maps all merged points
/// onto their true positions (least squares over every inlier point of every sweep: the common frame is
/// not observable from the sweeps, so it is removed).
struct Figures {
  double rms_mm = 0.0;                             ///< RMS over all inlier points of |G T_k x - T_true_k x|
  double max_mm = 0.0;                             ///< the largest such displacement
  std::vector<double> sweep_rms_mm;                ///< per sweep, the RMS
  std::vector<double> rotation_deg;                ///< per sweep, the angle of (G T_k) T_true_k^-1
  std::vector<double> translation_mm;              ///< per sweep, its translation at the sweep's centroid
  std::vector<Eigen::Matrix<double, 6, 1>> twist;  ///< per sweep (rotation x radius mm; translation mm)
  /// The shape: distance from the true surface of every 7th inlier's noise-free point as the merge placed
  /// it (after G), RMS and max (mm). A sweep that slid along a surface it fits moves its points (rms_mm)
  /// but not the shape; this is the issue-13 "shape error after a rigid fit".
  double shape_rms_mm = 0.0, shape_max_mm = 0.0;
  std::vector<double> sweep_shape_rms_mm;  ///< per sweep, the shape RMS
  /// The same over the points whose nearest point of the true surface is not on the patch's edge: a
  /// point that slid beyond the edge is measured there by its distance to the edge, along the surface,
  /// which is not shape (the max above is mostly such points on 8-sweep scans).
  double interior_shape_rms_mm = 0.0, interior_shape_max_mm = 0.0;
  /// The shape after the rigid motion that best fits the placed points to the true surface itself (their
  /// distances to it, least squares over the points whose foot is inside the patch): the fit a shape
  /// comparison makes when the correspondences are not known. G above also weighs how far each sweep slid
  /// along the surface, which is pose, not shape, and can tilt the whole to undo a slide.
  double surface_fit_shape_rms_mm = 0.0, surface_fit_shape_max_mm = 0.0;
  double surface_fit_interior_shape_rms_mm = 0.0,
         surface_fit_interior_shape_max_mm = 0.0;  ///< inside the patch
  Rigid3 G = Rigid3::Identity();                   ///< the common rigid motion removed
};

/// The noise-free hit of every inlier of a sweep, in the sweep's (reported) frame, #points by 3.
inline Points3 TrueInliers(const datasets::Sweep& s) {
  const Rigid3 T_sweep_scan = s.truth.T_scan_sweep.inverse();
  std::vector<Eigen::Index> keep;
  for (Eigen::Index i = 0; i < s.cloud.size(); ++i)
    if (!s.truth.outlier[static_cast<std::size_t>(i)]) keep.push_back(i);
  Points3 p(static_cast<Eigen::Index>(keep.size()), 3);
  for (std::size_t k = 0; k < keep.size(); ++k)
    p.row(static_cast<Eigen::Index>(k)) =
        (T_sweep_scan * Eigen::Vector3d(s.truth.true_points.row(keep[k]).transpose())).transpose();
  return p;
}

/// Adds the shape figures to `f` (see Figures::shape_rms_mm and interior_shape_rms_mm).
inline void EvaluateShape(const datasets::ChestSurface& surface, const std::vector<Points3>& true_inliers,
                          const std::vector<Rigid3>& placed, Figures* f) {
  double sum = 0.0, count = 0.0, interior_sum = 0.0, interior_count = 0.0;
  f->shape_max_mm = f->interior_shape_max_mm = 0.0;
  f->sweep_shape_rms_mm.clear();
  for (std::size_t s = 0; s < true_inliers.size(); ++s) {
    double sweep_sum = 0.0, sweep_count = 0.0;
    for (Eigen::Index i = 0; i < true_inliers[s].rows(); i += 7) {
      const datasets::ClosestPointResult foot =
          datasets::ClosestPoint(surface, placed[s] * Eigen::Vector3d(true_inliers[s].row(i).transpose()));
      const double d = std::abs(foot.signed_distance);
      sweep_sum += d * d;
      sweep_count += 1.0;
      f->shape_max_mm = std::max(f->shape_max_mm, d);
      if (!foot.on_boundary) {
        interior_sum += d * d;
        interior_count += 1.0;
        f->interior_shape_max_mm = std::max(f->interior_shape_max_mm, d);
      }
    }
    sum += sweep_sum;
    count += sweep_count;
    f->sweep_shape_rms_mm.push_back(std::sqrt(sweep_sum / std::max(1.0, sweep_count)));
  }
  f->shape_rms_mm = std::sqrt(sum / std::max(1.0, count));
  f->interior_shape_rms_mm = std::sqrt(interior_sum / std::max(1.0, interior_count));
}

/// Adds Figures::surface_fit_shape_rms_mm and _max_mm: Gauss-Newton on the point-to-surface distances of
/// every 7th noise-free point as placed, from `placed` (G already applied), a few steps.
inline void EvaluateShapeAfterSurfaceFit(const datasets::ChestSurface& surface,
                                         const std::vector<Points3>& true_inliers,
                                         const std::vector<Rigid3>& placed, Figures* f) {
  std::vector<Eigen::Vector3d> x;
  for (std::size_t s = 0; s < true_inliers.size(); ++s)
    for (Eigen::Index i = 0; i < true_inliers[s].rows(); i += 7)
      x.push_back(placed[s] * Eigen::Vector3d(true_inliers[s].row(i).transpose()));
  if (x.empty()) return;
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  for (const auto& p : x) c += p;
  c /= double(x.size());
  Rigid3 H = Rigid3::Identity();
  for (int iteration = 0; iteration < 6; ++iteration) {
    Eigen::Matrix<double, 6, 6> A = Eigen::Matrix<double, 6, 6>::Zero();
    Eigen::Matrix<double, 6, 1> b = Eigen::Matrix<double, 6, 1>::Zero();
    for (const auto& p0 : x) {
      const Eigen::Vector3d p = H * p0;
      const datasets::ClosestPointResult foot = datasets::ClosestPoint(surface, p);
      if (foot.on_boundary) continue;
      Eigen::Matrix<double, 6, 1> J;
      J << (p - c).cross(foot.normal), foot.normal;
      A += J * J.transpose();
      b += J * foot.signed_distance;
    }
    const Eigen::Matrix<double, 6, 1> step = -A.ldlt().solve(b);
    if (!step.allFinite()) break;
    Rigid3 D = Rigid3::Identity();
    const double angle = step.head<3>().norm();
    if (angle > 0.0) D.linear() = Eigen::AngleAxisd(angle, step.head<3>() / angle).toRotationMatrix();
    D.translation() = c - D.linear() * c + step.tail<3>();
    H = D * H;
    if (step.tail<3>().norm() < 1e-7 && angle < 1e-9) break;
  }
  std::vector<Rigid3> refit;
  for (const Rigid3& T : placed) refit.push_back(H * T);
  Figures g;
  EvaluateShape(surface, true_inliers, refit, &g);
  f->surface_fit_shape_rms_mm = g.shape_rms_mm;
  f->surface_fit_shape_max_mm = g.shape_max_mm;
  f->surface_fit_interior_shape_rms_mm = g.interior_shape_rms_mm;
  f->surface_fit_interior_shape_max_mm = g.interior_shape_max_mm;
}

/// Inlier points (reported frame) of a sweep, #points by 3.
inline Points3 Inliers(const datasets::Sweep& s) {
  std::vector<Eigen::Index> keep;
  for (Eigen::Index i = 0; i < s.cloud.size(); ++i)
    if (!s.truth.outlier[static_cast<std::size_t>(i)]) keep.push_back(i);
  Points3 p(static_cast<Eigen::Index>(keep.size()), 3);
  for (std::size_t k = 0; k < keep.size(); ++k)
    p.row(static_cast<Eigen::Index>(k)) = s.cloud.positions.row(keep[k]);
  return p;
}

/// Centroid and RMS radius of points (the lever that turns a rotation into mm).
inline void CentroidAndRadius(const Points3& p, Eigen::Vector3d* c, double* radius) {
  *c = p.colwise().mean().transpose();
  *radius = std::sqrt((p.rowwise() - c->transpose()).rowwise().squaredNorm().mean());
}

inline Figures Evaluate(const std::vector<Points3>& inliers, const std::vector<Rigid3>& estimate,
                        const std::vector<Rigid3>& truth) {
  Eigen::Index n = 0;
  std::vector<PointCloud> clouds(inliers.size());
  for (std::size_t s = 0; s < inliers.size(); ++s) clouds[s].positions = inliers[s], n += inliers[s].rows();
  const Rigid3 G = BestCommonMotion(clouds, estimate, truth);
  Figures f;
  f.G = G;
  double total = 0.0;
  for (std::size_t s = 0; s < inliers.size(); ++s) {
    const Rigid3 placed = G * estimate[s];
    double sum = 0.0;
    for (Eigen::Index i = 0; i < inliers[s].rows(); ++i) {
      const Eigen::Vector3d x = inliers[s].row(i).transpose();
      const double d2 = (placed * x - truth[s] * x).squaredNorm();
      sum += d2;
      f.max_mm = std::max(f.max_mm, std::sqrt(d2));
    }
    total += sum;
    f.sweep_rms_mm.push_back(std::sqrt(sum / std::max<double>(1.0, inliers[s].rows())));
    // The error D = placed truth^-1 moves each true point to where the merge put it; as a twist about the
    // sweep's true centroid c: rotation vector times the sweep's RMS radius, and D(c) - c.
    Eigen::Vector3d c;
    double radius = 0.0;
    const Points3 true_points =
        (inliers[s] * truth[s].linear().transpose()).rowwise() + truth[s].translation().transpose();
    CentroidAndRadius(true_points, &c, &radius);
    const Rigid3 D = placed * truth[s].inverse();
    const Eigen::AngleAxisd aa(D.linear());
    f.rotation_deg.push_back(aa.angle() * 180.0 / M_PI);
    f.translation_mm.push_back((D * c - c).norm());
    Eigen::Matrix<double, 6, 1> e;
    e << aa.angle() * aa.axis() * radius, D * c - c;
    f.twist.push_back(e);
  }
  f.rms_mm = std::sqrt(total / std::max<double>(1.0, static_cast<double>(n)));
  return f;
}

/// How well a sweep's overlaps with the others pin its pose: the point-to-plane information matrix
/// H = sum J^T J / m over m of its true points that have a true point of another sweep within 2 mm,
/// J = [((p - c) / radius x n)^T, n^T] (n the exact normal), so that both blocks are in mm. Its
/// eigenvalues (ascending, divided by the largest) and the merge error's components along its
/// eigenvectors (mm): the smallest eigenvalue's direction is the one the overlaps pin least.
struct Constraint {
  Eigen::Matrix<double, 6, 1> eigenvalue_ratio = Eigen::Matrix<double, 6, 1>::Zero();
  Eigen::Matrix<double, 6, 6> directions = Eigen::Matrix<double, 6, 6>::Identity();  ///< columns
  double overlap_points = 0.0;                                                       ///< m
};

inline std::vector<Constraint> OverlapConstraints(const datasets::ChestSurface& surface,
                                                  const std::vector<datasets::Sweep>& sweeps) {
  std::vector<Constraint> out(sweeps.size());
  for (std::size_t s = 0; s < sweeps.size(); ++s) {
    Eigen::Index others = 0;
    for (std::size_t t = 0; t < sweeps.size(); ++t)
      if (t != s) others += sweeps[t].truth.true_points.rows();
    Points3 other(others, 3);
    Eigen::Index k = 0;
    for (std::size_t t = 0; t < sweeps.size(); ++t) {
      if (t == s) continue;
      other.middleRows(k, sweeps[t].truth.true_points.rows()) = sweeps[t].truth.true_points;
      k += sweeps[t].truth.true_points.rows();
    }
    const datasets::SweepTruth& truth = sweeps[s].truth;
    Eigen::Vector3d c;
    double radius = 0.0;
    CentroidAndRadius(truth.true_points, &c, &radius);
    Eigen::Matrix<double, 6, 6> H = Eigen::Matrix<double, 6, 6>::Zero();
    if (others > 0) {
      const KdTree3 tree(other);
      const Eigen::Index step = std::max<Eigen::Index>(1, truth.true_points.rows() / 4000);
      for (Eigen::Index i = 0; i < truth.true_points.rows(); i += step) {
        const Eigen::Vector3d p = truth.true_points.row(i).transpose();
        std::uint32_t nearest = 0;
        double d2 = 0.0;
        if (!tree.Nearest(p, &nearest, &d2) || d2 > 4.0) continue;
        const Eigen::Vector3d n = surface.Evaluate(truth.u(i), truth.v(i)).normal;
        Eigen::Matrix<double, 6, 1> J;
        J << ((p - c) / radius).cross(n), n;
        H += J * J.transpose();
        out[s].overlap_points += 1.0;
      }
    }
    if (out[s].overlap_points > 0) H /= out[s].overlap_points;
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 6, 6>> eig(H);
    const double largest = std::max(eig.eigenvalues()(5), 1e-300);
    out[s].eigenvalue_ratio = eig.eigenvalues() / largest;
    out[s].directions = eig.eigenvectors();
  }
  return out;
}

}  // namespace pectus::merge_grid
