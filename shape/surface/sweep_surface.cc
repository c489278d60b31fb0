#include "shape/surface/sweep_surface.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <unordered_map>

#include "registration/estimate_normals.h"
#include "registration/voxel_downsample.h"
#include "shape/core/error.h"

namespace pectus {
namespace {

// Border points (the sweep's edge or the rim of a hole): the largest angle between successive neighbours
// around the point, in its tangent plane, exceeds `max_gap_rad` (the angle criterion of PCL's
// BoundaryEstimation; Bendels et al. 2006). It holds for any sampling: a regular grid leaves gaps of 45 to
// 90 degrees inside, and k uniformly random neighbours leave a gap wider than 135 degrees with
// probability about k (5/8)^(k-1) (0.05 % for k = 24), while an edge leaves about 180 degrees.
std::vector<std::uint8_t> FindBorder(const Points3& points, const Points3& normals, const KdTree3& tree,
                                     int k, double max_gap_rad) {
  const Eigen::Index n = points.rows();
  std::vector<std::uint8_t> border(static_cast<std::size_t>(n), 0);
#pragma omp parallel
  {
    std::vector<std::uint32_t> idx(static_cast<std::size_t>(k));
    std::vector<double> d2(static_cast<std::size_t>(k));
    std::vector<double> angles;
    angles.reserve(static_cast<std::size_t>(k));
#pragma omp for schedule(dynamic, 2048)
    for (Eigen::Index i = 0; i < n; ++i) {
      const Eigen::Vector3d p = points.row(i).transpose();
      const Eigen::Vector3d nv = normals.row(i).transpose();
      const int found = tree.Knn(p, k, idx.data(), d2.data());
      if (found < 4 || nv.squaredNorm() < 0.5) {
        border[std::size_t(i)] = 1;
        continue;
      }
      // An orthonormal frame (u, v) of the tangent plane.
      const Eigen::Vector3d u = nv.unitOrthogonal();
      const Eigen::Vector3d v = nv.cross(u);
      angles.clear();
      for (int j = 0; j < found; ++j) {
        const Eigen::Vector3d d = points.row(idx[std::size_t(j)]).transpose() - p;
        const double du = d.dot(u), dv = d.dot(v);
        if (du * du + dv * dv > 0.0) angles.push_back(std::atan2(dv, du));
      }
      if (angles.size() < 3) {
        border[std::size_t(i)] = 1;
        continue;
      }
      std::sort(angles.begin(), angles.end());
      double gap = angles.front() + 2.0 * M_PI - angles.back();
      for (std::size_t j = 1; j < angles.size(); ++j) gap = std::max(gap, angles[j] - angles[j - 1]);
      border[std::size_t(i)] = gap > max_gap_rad;
    }
  }
  return border;
}

// Per point, the mean of the normals over a cube of half side `radius_widths` sweep widths about it
// (SweepSurfaceOptions::sight_radius_widths; the width across `view`), from sums over voxels of half that
// side: every point takes its voxel's line of sight. `view` (the sweep's mean normal) where the mean
// vanishes or radius_widths is 0.
Points3 LinesOfSight(const Points3& points, const Points3& normals, const Eigen::Vector3d& view,
                     double radius_widths) {
  Points3 sight(points.rows(), 3);
  sight.rowwise() = view.transpose();
  if (!(radius_widths > 0.0) || points.rows() < 3) return sight;
  // The width across the line of sight: the points projected on the plane normal to `view`, their
  // narrow principal axis (the projected covariance's middle eigenvalue; the smallest is along `view`).
  const Eigen::RowVector3d mean = points.colwise().mean();
  const Eigen::Matrix3d across = Eigen::Matrix3d::Identity() - view * view.transpose();
  const Eigen::Matrix3d cov = across * (points.rowwise() - mean).transpose() * (points.rowwise() - mean) *
                              across / double(points.rows());
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> pca(cov);
  const double radius = radius_widths * std::sqrt(12.0 * std::max(0.0, pca.eigenvalues()(1)));
  const double length = std::sqrt(12.0 * std::max(0.0, pca.eigenvalues()(2)));
  // A sweep about as thin as a line has no width to follow (and voxel indices must fit the key's 21 bits).
  if (!(radius > 1e-5 * length) || !std::isfinite(radius)) return sight;
  const double side = radius / 2.0;
  auto voxel = [&](Eigen::Index r) {
    const Eigen::RowVector3d x = (points.row(r) - mean) / side;
    return Eigen::Vector3i(int(std::floor(x.x())), int(std::floor(x.y())), int(std::floor(x.z())));
  };
  auto key = [](const Eigen::Vector3i& v) {
    return (std::uint64_t(std::uint32_t(v.x() + (1 << 20))) << 42) |
           (std::uint64_t(std::uint32_t(v.y() + (1 << 20))) << 21) |
           std::uint64_t(std::uint32_t(v.z() + (1 << 20)));
  };
  std::unordered_map<std::uint64_t, Eigen::Vector3d> sums;
  for (Eigen::Index r = 0; r < points.rows(); ++r) {
    auto [it, added] = sums.try_emplace(key(voxel(r)), Eigen::Vector3d::Zero());
    it->second += normals.row(r).transpose();
  }
  std::unordered_map<std::uint64_t, Eigen::Vector3d> voxel_sight;
  for (Eigen::Index r = 0; r < points.rows(); ++r) {
    const Eigen::Vector3i v = voxel(r);
    auto [it, added] = voxel_sight.try_emplace(key(v), Eigen::Vector3d::Zero());
    if (added) {
      Eigen::Vector3d sum = Eigen::Vector3d::Zero();
      for (int dx = -2; dx <= 2; ++dx)
        for (int dy = -2; dy <= 2; ++dy)
          for (int dz = -2; dz <= 2; ++dz) {
            const auto found = sums.find(key(v + Eigen::Vector3i(dx, dy, dz)));
            if (found != sums.end()) sum += found->second;
          }
      it->second = sum.norm() > 1e-9 ? Eigen::Vector3d(sum.normalized()) : view;
    }
    sight.row(r) = it->second.transpose();
  }
  return sight;
}

// Whether the scanner moved along the sweep, from its sampling: a scanner standing still samples a surface
// turned by theta from its line of sight at cos(theta) of the density it gives one facing it, a wand
// carried along the sweep facing the skin samples it evenly. The median density (1 / the squared distance
// to the 8th neighbour, over at most 3000 points) 55-80 degrees from the sweep's mean normal `view`, over
// that within 30 degrees, at least `min_ratio`; false when either holds fewer than 20 points (nothing
// much to see at a grazing angle) or min_ratio is > 1.
bool ScannerMovedAlongSweep(const Points3& points, const Points3& normals, const KdTree3& tree,
                            const Eigen::Vector3d& view, double min_ratio) {
  if (min_ratio > 1.0) return false;
  if (!(min_ratio > 0.0)) return true;
  const Eigen::Index stride = std::max<Eigen::Index>(1, points.rows() / 3000);
  const double head_on = std::cos(30.0 * M_PI / 180.0), near = std::cos(55.0 * M_PI / 180.0),
               far = std::cos(80.0 * M_PI / 180.0);
  std::vector<double> facing, turned;
  std::uint32_t index[9];
  double d2[9];
  for (Eigen::Index r = 0; r < points.rows(); r += stride) {
    const double c = std::abs(normals.row(r).dot(view.transpose()));
    if (c < head_on && (c > near || c < far)) continue;
    if (tree.Knn(points.row(r).transpose(), 9, index, d2) < 9 || !(d2[8] > 0.0)) continue;
    (c >= head_on ? facing : turned).push_back(1.0 / d2[8]);
  }
  if (facing.size() < 20 || turned.size() < 20) return false;
  auto median = [](std::vector<double>* v) {
    std::nth_element(v->begin(), v->begin() + std::ptrdiff_t(v->size() / 2), v->end());
    return (*v)[v->size() / 2];
  };
  return median(&turned) >= min_ratio * median(&facing);
}

}  // namespace

bool SweepSurfaceOptions::IsValid(std::string* why) const {
  auto fail = [&](const char* text) {
    if (why) *why = text;
    return false;
  };
  if (normal_neighbours < 3 || normal_neighbours > 256) return fail("normal neighbours must be in [3, 256]");
  if (border_neighbours < 4 || border_neighbours > 256) return fail("border neighbours must be in [4, 256]");
  if (!(border_gap_deg >= 90.0 && border_gap_deg < 180.0)) return fail("border gap must be in [90, 180)");
  if (!(max_view_angle_deg > 0.0 && max_view_angle_deg <= 90.0))
    return fail("max view angle must be in (0, 90]");
  if (!(view_weight_power >= 0.0 && view_weight_power <= 8.0))
    return fail("view weight power must be in [0, 8]");
  if (!(moving_scanner_density_ratio >= 0.0) || !std::isfinite(moving_scanner_density_ratio))
    return fail("moving scanner density ratio must be >= 0");
  if (!(sight_radius_widths >= 0.0 && sight_radius_widths <= 100.0))
    return fail("sight radius must be in [0, 100] sweep widths");
  static_assert(kMaxPlanePoints == 4, "the message below");
  if (plane_points < 1 || plane_points > kMaxPlanePoints) return fail("plane points must be in [1, 4]");
  if (!(sample_spacings >= 1.0) || !std::isfinite(sample_spacings))
    return fail("sample spacings must be >= 1");
  return true;
}

void SweepSurface::FlipNormals() { normals *= -1.0; }

SweepSurface PrepareSweep(const PointCloud& cloud, const SweepSurfaceOptions& options,
                          const std::string& name) {
  std::string why;
  if (!options.IsValid(&why)) ThrowUsage("sweep preparation: " + why);
  if (cloud.size() < 10) ThrowBadInput(name, "has " + std::to_string(cloud.size()) + " points (< 10)");
  cloud.Validate(name);
  SweepSurface s;
  s.cloud = &cloud;
  s.plane_points = options.plane_points;
  const KdTree3 tree(cloud.positions);
  NormalOptions no;
  no.k = options.normal_neighbours;
  no.orientation = NormalOrientation::kPropagate;
  NormalResult estimated = EstimateNormals(cloud.positions, no, &tree);
  s.normals = std::move(estimated.normals);
  {
    std::vector<double> c(estimated.curvature.data(),
                          estimated.curvature.data() + estimated.curvature.size());
    std::nth_element(c.begin(), c.begin() + std::ptrdiff_t(c.size() / 2), c.end());
    s.normal_variance = 2.0 * c[c.size() / 2] / double(options.normal_neighbours);
  }
  s.border = FindBorder(cloud.positions, s.normals, tree, options.border_neighbours,
                        options.border_gap_deg * M_PI / 180.0);
  s.grazing.assign(s.border.size(), 0);
  s.confidence.assign(s.border.size(), 1.0f);
  {
    // A sweep sees only surfaces that face the scanner: every normal is turned to the side of the line of
    // sight where it was seen (sight_radius_widths; the sweep's mean normal by default), from the
    // propagated normals (propagation alone can flip a part across a fold).
    const Eigen::Vector3d view = s.normals.colwise().sum().transpose().normalized();
    s.scanner_moved =
        ScannerMovedAlongSweep(cloud.positions, s.normals, tree, view, options.moving_scanner_density_ratio);
    const Points3 sight =
        LinesOfSight(cloud.positions, s.normals, view, s.scanner_moved ? options.sight_radius_widths : 0.0);
    for (Eigen::Index r = 0; r < s.normals.rows(); ++r) {
      if (s.normals.row(r).dot(sight.row(r)) < 0.0) s.normals.row(r) *= -1.0;
    }
    // The view angle against that line of sight.
    const double min_cos = std::cos(options.max_view_angle_deg * M_PI / 180.0);
    for (Eigen::Index r = 0; r < s.normals.rows(); ++r) {
      const double c = std::abs(s.normals.row(r).dot(sight.row(r)));
      if (c < min_cos) s.grazing[std::size_t(r)] = 1;
      if (options.view_weight_power > 0.0)
        s.confidence[std::size_t(r)] = float(std::pow(c, options.view_weight_power));
    }
  }
  Points3 target_normals = s.normals;
  for (Eigen::Index r = 0; r < target_normals.rows(); ++r) {
    if (s.border[std::size_t(r)] || s.grazing[std::size_t(r)]) target_normals.row(r).setZero();
  }
  s.target = std::make_unique<IcpTarget>(cloud.positions, target_normals, name);
  s.spacing_mm = s.target->spacing_mm();
  s.centroid = s.target->origin();
  s.samples = VoxelDownsample(cloud.positions, std::max(1e-3, options.sample_spacings * s.spacing_mm));
  return s;
}

std::vector<SweepCorrespondence> FindSweepCorrespondences(const std::vector<SweepSurface>& sweeps,
                                                          const std::vector<Rigid3>& T_world_sweep,
                                                          std::size_t i, std::size_t j, int max_samples,
                                                          double gate_mm, double max_angle_deg) {
  return FindSweepCorrespondences(sweeps, T_world_sweep, i, j, sweeps[j].samples, std::max(1, max_samples),
                                  gate_mm, max_angle_deg);
}

std::vector<SweepCorrespondence> FindSweepCorrespondences(const std::vector<SweepSurface>& sweeps,
                                                          const std::vector<Rigid3>& T_world_sweep,
                                                          std::size_t i, std::size_t j,
                                                          const std::vector<std::uint32_t>& rows,
                                                          int max_samples, double gate_mm,
                                                          double max_angle_deg) {
  const SweepSurface& a = sweeps[i];
  const SweepSurface& b = sweeps[j];
  const Rigid3 T_i_j = T_world_sweep[i].inverse() * T_world_sweep[j];
  const std::size_t n = rows.size();
  const std::size_t stride = max_samples > 0 ? std::max<std::size_t>(1, n / std::size_t(max_samples)) : 1;
  const double gate2 = gate_mm * gate_mm;
  const double min_cos = std::cos(max_angle_deg * M_PI / 180.0);
  std::vector<SweepCorrespondence> out;
  out.reserve(n / stride + 1);
  for (std::size_t s = 0; s < n; s += stride) {
    const std::uint32_t r = rows[s];
    const Eigen::Vector3d p = b.cloud->positions.row(r).transpose();
    const Eigen::Vector3d x = T_i_j * p - a.target->origin();
    std::uint32_t near[kMaxPlanePoints];
    double d2[kMaxPlanePoints];
    const int found = a.plane_points == 1
                          ? (a.target->tree().NearestWithin(x, gate_mm, near, d2) ? 1 : 0)
                          : a.target->tree().NearestWithin(x, gate_mm, a.plane_points, near, d2);
    if (found == 0 || d2[0] > gate2) continue;
    const std::uint32_t k = near[0];
    if (a.border[k] || a.grazing[k] || b.grazing[r]) continue;
    const Eigen::Vector3d nq = a.normals.row(k).transpose();
    const Eigen::Vector3d np = T_i_j.linear() * b.normals.row(r).transpose();
    if (nq.squaredNorm() < 0.5 || np.squaredNorm() < 0.5 || np.dot(nq) < min_cos) continue;
    // A pair more than a point spacing apart along the tangent plane is a point beyond i's edge paired
    // with the edge: the plane extrapolated there misses a curved surface (by curvature * d^2 / 2).
    Eigen::Vector3d q = a.target->centred_positions().row(k).transpose();  // i's frame, centred
    const Eigen::Vector3d d = x - q;
    if ((d - nq.dot(d) * nq).squaredNorm() > a.spacing_mm * a.spacing_mm) continue;
    // The plane through the nearest points of i (SweepSurfaceOptions::plane_points).
    Eigen::Vector3d plane_normal = nq;
    PlaneThroughNearestPoints(
        a.target->centred_positions(), a.normals, near, found,
        [&](std::uint32_t row) {
          return !a.border[row] && !a.grazing[row] && a.normals.row(row).squaredNorm() >= 0.5;
        },
        &q, &plane_normal);
    q += a.target->origin();
    out.push_back(
        {i, j, p, q, plane_normal, std::max(1e-3, double(a.confidence[k]) * double(b.confidence[r])), r, k});
  }
  return out;
}

double PointToPlaneRms(const std::vector<SweepCorrespondence>& pairs,
                       const std::vector<Rigid3>& T_world_sweep) {
  if (pairs.empty()) return 0.0;
  double sum = 0.0;
  for (const auto& c : pairs) {
    const double r =
        (T_world_sweep[c.i].linear() * c.n).dot(T_world_sweep[c.j] * c.p - T_world_sweep[c.i] * c.q);
    sum += r * r;
  }
  return std::sqrt(sum / double(pairs.size()));
}

}  // namespace pectus
