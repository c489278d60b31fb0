#include "shape/surface/sweep_surface.h"

#include <algorithm>
#include <cmath>

#include "registration/estimate_normals.h"
#include "registration/voxel_downsample.h"
#include "shape/core/error.h"

namespace pectus {
namespace {

// Border points: the mean of the k nearest neighbours, projected on the tangent plane, lies off the
// point by more than `shift` of the neighbours' mean distance.
std::vector<std::uint8_t> FindBorder(const Points3& points, const Points3& normals, const KdTree3& tree,
                                     int k, double shift) {
  const Eigen::Index n = points.rows();
  std::vector<std::uint8_t> border(static_cast<std::size_t>(n), 0);
#pragma omp parallel
  {
    std::vector<std::uint32_t> idx(static_cast<std::size_t>(k));
    std::vector<double> d2(static_cast<std::size_t>(k));
#pragma omp for schedule(dynamic, 2048)
    for (Eigen::Index i = 0; i < n; ++i) {
      const Eigen::Vector3d p = points.row(i).transpose();
      const Eigen::Vector3d nv = normals.row(i).transpose();
      const int found = tree.Knn(p, k, idx.data(), d2.data());
      Eigen::Vector3d mean = Eigen::Vector3d::Zero();
      double mean_distance = 0.0;
      for (int j = 0; j < found; ++j) {
        mean += points.row(idx[std::size_t(j)]).transpose() - p;
        mean_distance += std::sqrt(d2[std::size_t(j)]);
      }
      if (found < 4 || nv.squaredNorm() < 0.5) {
        border[std::size_t(i)] = 1;
        continue;
      }
      mean /= double(found - 1);  // the point itself adds nothing
      mean_distance /= double(found - 1);
      const Eigen::Vector3d tangential = mean - nv.dot(mean) * nv;
      border[std::size_t(i)] = tangential.norm() > shift * mean_distance;
    }
  }
  return border;
}

}  // namespace

bool SweepSurfaceOptions::IsValid(std::string* why) const {
  auto fail = [&](const char* text) {
    if (why) *why = text;
    return false;
  };
  if (normal_neighbours < 3 || normal_neighbours > 256) return fail("normal neighbours must be in [3, 256]");
  if (border_neighbours < 4 || border_neighbours > 256) return fail("border neighbours must be in [4, 256]");
  if (!(border_shift > 0.0 && border_shift < 1.0)) return fail("border shift must be in (0, 1)");
  if (!(max_view_angle_deg > 0.0 && max_view_angle_deg <= 90.0))
    return fail("max view angle must be in (0, 90]");
  if (!(view_weight_power >= 0.0 && view_weight_power <= 8.0))
    return fail("view weight power must be in [0, 8]");
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
  const KdTree3 tree(cloud.positions);
  NormalOptions no;
  no.k = options.normal_neighbours;
  no.orientation = NormalOrientation::kPropagate;
  s.normals = EstimateNormals(cloud.positions, no, &tree).normals;
  s.border = FindBorder(cloud.positions, s.normals, tree, options.border_neighbours, options.border_shift);
  s.grazing.assign(s.border.size(), 0);
  s.confidence.assign(s.border.size(), 1.0f);
  {
    // A sweep sees only surfaces that face the scanner: every normal is turned to the side of the sweep's
    // mean normal, which stands for the line of sight (propagation alone can flip a part across a fold).
    const Eigen::Vector3d view = s.normals.colwise().sum().transpose().normalized();
    for (Eigen::Index r = 0; r < s.normals.rows(); ++r) {
      if (s.normals.row(r).dot(view.transpose()) < 0.0) s.normals.row(r) *= -1.0;
    }
    const double min_cos = std::cos(options.max_view_angle_deg * M_PI / 180.0);
    for (Eigen::Index r = 0; r < s.normals.rows(); ++r) {
      const double c = std::abs(s.normals.row(r).dot(view.transpose()));
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
  const SweepSurface& a = sweeps[i];
  const SweepSurface& b = sweeps[j];
  const Rigid3 T_i_j = T_world_sweep[i].inverse() * T_world_sweep[j];
  const std::size_t n = b.samples.size();
  const std::size_t stride = std::max<std::size_t>(1, n / std::size_t(std::max(1, max_samples)));
  const double gate2 = gate_mm * gate_mm;
  const double min_cos = std::cos(max_angle_deg * M_PI / 180.0);
  std::vector<SweepCorrespondence> out;
  out.reserve(n / stride + 1);
  for (std::size_t s = 0; s < n; s += stride) {
    const std::uint32_t r = b.samples[s];
    const Eigen::Vector3d p = b.cloud->positions.row(r).transpose();
    std::uint32_t k;
    double d2;
    if (!a.target->tree().NearestWithin(T_i_j * p - a.target->origin(), gate_mm, &k, &d2) || d2 > gate2)
      continue;
    if (a.border[k] || a.grazing[k] || b.grazing[r]) continue;
    const Eigen::Vector3d nq = a.normals.row(k).transpose();
    const Eigen::Vector3d np = T_i_j.linear() * b.normals.row(r).transpose();
    if (nq.squaredNorm() < 0.5 || np.squaredNorm() < 0.5 || np.dot(nq) < min_cos) continue;
    // A pair more than a point spacing apart along the tangent plane is a point beyond i's edge paired
    // with the edge: the plane extrapolated there misses a curved surface (by curvature * d^2 / 2).
    const Eigen::Vector3d q = a.target->centred_positions().row(k).transpose() + a.target->origin();
    const Eigen::Vector3d d = T_i_j * p - q;
    if ((d - nq.dot(d) * nq).squaredNorm() > a.spacing_mm * a.spacing_mm) continue;
    out.push_back({i, j, p, q, nq, std::max(1e-3, double(a.confidence[k]) * double(b.confidence[r]))});
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
