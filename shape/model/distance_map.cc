#include "shape/model/distance_map.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <sstream>
#include <vector>

#include "registration/kdtree.h"
#include "shape/core/closest_point_on_triangle.h"
#include "shape/core/enum_names.h"
#include "shape/core/error.h"
#include "shape/core/sample_statistics.h"

namespace pectus {
namespace {

// Face, edge and angle-weighted vertex pseudo-normals of a mesh.
struct PseudoNormals {
  Points3 face, vertex;
  std::map<std::pair<int, int>, Eigen::Vector3d> edge;

  explicit PseudoNormals(const TriangleMesh& mesh) {
    const Points3& x = mesh.vertices.positions;
    face = Points3::Zero(mesh.num_faces(), 3);
    vertex = Points3::Zero(mesh.num_vertices(), 3);
    for (Eigen::Index f = 0; f < mesh.num_faces(); ++f) {
      const int i[3] = {mesh.faces(f, 0), mesh.faces(f, 1), mesh.faces(f, 2)};
      const Eigen::Vector3d n = (x.row(i[1]) - x.row(i[0])).cross(x.row(i[2]) - x.row(i[0])).transpose();
      if (n.norm() == 0.0) continue;
      face.row(f) = n.normalized().transpose();
      for (int c = 0; c < 3; ++c) {
        const Eigen::Vector3d e1 = (x.row(i[(c + 1) % 3]) - x.row(i[c])).transpose();
        const Eigen::Vector3d e2 = (x.row(i[(c + 2) % 3]) - x.row(i[c])).transpose();
        const double angle = std::atan2(e1.cross(e2).norm(), e1.dot(e2));
        vertex.row(i[c]) += angle * face.row(f);
        // (operator[] would leave a new Eigen vector uninitialised)
        auto [it, unused] = edge.try_emplace(Key(i[c], i[(c + 1) % 3]), Eigen::Vector3d::Zero());
        it->second += face.row(f).transpose();
      }
    }
  }
  static std::pair<int, int> Key(int a, int b) { return {std::min(a, b), std::max(a, b)}; }
  Eigen::Vector3d At(const TriangleMesh& mesh, Eigen::Index f, int feature) const {
    const int i[3] = {mesh.faces(f, 0), mesh.faces(f, 1), mesh.faces(f, 2)};
    if (feature < 3) return vertex.row(i[feature]).transpose();
    if (feature < 6) return edge.at(Key(i[feature - 3], i[(feature - 2) % 3]));
    return face.row(f).transpose();
  }
};

constexpr EnumNames<DistanceKind, 2> kKindNames{
    {{DistanceKind::kNearestPoint, "nearest"}, {DistanceKind::kSignedSurface, "signed"}}};
}  // namespace

DistanceKind ParseDistanceKind(const std::string& text) {
  return ParseEnum(kKindNames, text, [&] {
    return "distance kind '" + text + "' is not " + ListEnumNames(kKindNames, "'", ", ", " or ");
  });
}

std::string ToString(DistanceKind kind) { return EnumToString(kKindNames, kind, "signed"); }

nlohmann::json DistanceStats::ToJson() const {
  return {{"count", count},    {"min_mm", min},           {"max_mm", max},    {"max_abs_mm", max_abs},
          {"mean_mm", mean},   {"mean_abs_mm", mean_abs}, {"rms_mm", rms},    {"p50_abs_mm", p50},
          {"p90_abs_mm", p90}, {"p95_abs_mm", p95},       {"p99_abs_mm", p99}};
}

DistanceStats SummarizeDistances(const Eigen::VectorXd& d) {
  DistanceStats s;
  s.count = d.size();
  if (d.size() == 0) return s;
  s.min = d.minCoeff();
  s.max = d.maxCoeff();
  s.max_abs = d.cwiseAbs().maxCoeff();
  s.mean = d.mean();
  s.mean_abs = d.cwiseAbs().mean();
  s.rms = std::sqrt(d.squaredNorm() / static_cast<double>(d.size()));
  std::vector<double> a(static_cast<std::size_t>(d.size()));
  for (Eigen::Index k = 0; k < d.size(); ++k) a[static_cast<std::size_t>(k)] = std::abs(d[k]);
  const std::vector<double> q = Quantiles(std::move(a), {0.50, 0.90, 0.95, 0.99});
  s.p50 = q[0];
  s.p90 = q[1];
  s.p95 = q[2];
  s.p99 = q[3];
  return s;
}

DistanceMapResult ComputeDistanceMap(const Points3& points, const TriangleMesh& reference, DistanceKind kind,
                                     const std::string& what) {
  reference.Validate(what);
  if (reference.num_vertices() == 0) ThrowBadInput(what, "has no points to measure distances to");
  if (kind == DistanceKind::kSignedSurface && reference.num_faces() == 0) {
    ThrowBadInput(what, "has no triangles; a signed point-to-surface distance needs a mesh (use 'nearest')");
  }
  const Points3& x = reference.vertices.positions;
  const Eigen::Index n = points.rows();
  DistanceMapResult result;
  result.distances.resize(n);
  result.closest.resize(n, 3);

  if (kind == DistanceKind::kNearestPoint) {
    const KdTree3 tree(x);
#pragma omp parallel for schedule(static)
    for (Eigen::Index k = 0; k < n; ++k) {
      std::uint32_t index = 0;
      double d2 = 0.0;
      tree.Nearest(points.row(k).transpose(), &index, &d2);
      result.distances[k] = std::sqrt(d2);
      result.closest.row(k) = x.row(index);
    }
  } else {
    // Only vertices of triangles take part; faces around each, the longest edge, pseudo-normals for the sign.
    std::vector<std::int32_t> slot(static_cast<std::size_t>(reference.num_vertices()), -1);
    std::vector<std::vector<std::int32_t>> faces_of;
    std::vector<Eigen::Index> used;
    double longest = 0.0;
    for (Eigen::Index f = 0; f < reference.num_faces(); ++f) {
      for (int c = 0; c < 3; ++c) {
        const std::int32_t v = reference.faces(f, c);
        if (slot[v] < 0) {
          slot[v] = static_cast<std::int32_t>(used.size());
          used.push_back(v);
          faces_of.emplace_back();
        }
        faces_of[slot[v]].push_back(static_cast<std::int32_t>(f));
        longest = std::max(longest, (x.row(v) - x.row(reference.faces(f, (c + 1) % 3))).norm());
      }
    }
    Points3 used_points(static_cast<Eigen::Index>(used.size()), 3);
    for (std::size_t k = 0; k < used.size(); ++k)
      used_points.row(static_cast<Eigen::Index>(k)) = x.row(used[k]);
    const KdTree3 face_tree(used_points);
    const PseudoNormals normals(reference);
#pragma omp parallel for schedule(dynamic, 256)
    for (Eigen::Index k = 0; k < n; ++k) {
      const Eigen::Vector3d p = points.row(k).transpose();
      std::uint32_t index = 0;
      double d2 = 0.0;
      face_tree.Nearest(p, &index, &d2);
      // The closest surface point is within sqrt(d2) of p, so its triangle has a vertex within that plus
      // the longest edge.
      std::vector<std::pair<std::uint32_t, double>> near;
      face_tree.Radius(p, std::sqrt(d2) + longest + 1e-9, &near, false);
      double best = std::numeric_limits<double>::infinity();
      Eigen::Vector3d best_point = used_points.row(index).transpose(), best_normal = Eigen::Vector3d::Zero();
      for (const auto& [v, unused] : near) {
        for (std::int32_t f : faces_of[v]) {
          int feature = 6;
          const Eigen::Vector3d q = ClosestPointOnTriangle(
              p, x.row(reference.faces(f, 0)).transpose(), x.row(reference.faces(f, 1)).transpose(),
              x.row(reference.faces(f, 2)).transpose(), &feature);
          const double d = (p - q).squaredNorm();
          if (d < best) {
            best = d;
            best_point = q;
            best_normal = normals.At(reference, f, feature);
          }
        }
      }
      const double distance = std::sqrt(std::max(0.0, best));
      result.distances[k] = (p - best_point).dot(best_normal) < 0.0 ? -distance : distance;
      result.closest.row(k) = best_point.transpose();
    }
  }
  result.stats = SummarizeDistances(result.distances);
  std::ostringstream msg;
  msg << ToString(kind) << " distances of " << n << " points: max |d| " << result.stats.max_abs << " mm, RMS "
      << result.stats.rms << " mm, mean " << result.stats.mean << " mm";
  result.message = msg.str();
  return result;
}

}  // namespace pectus
