#include "planner_plugin/trainer/triangle_grid.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "shape/core/closest_point_on_triangle.h"
#include "shape/core/error.h"

namespace pectus::trainer {
namespace {

// A hair of slack on the barycentric test, so a segment through a shared edge meets one of its faces.
constexpr double kEdgeSlack = 1e-9;

// Möller-Trumbore: the line a + t (b - a) meets triangle (p0, p1, p2) at t (any t); false if parallel or
// outside the triangle.
bool LineTriangle(const Eigen::Vector3d& a, const Eigen::Vector3d& d, const Eigen::Vector3d& p0,
                  const Eigen::Vector3d& p1, const Eigen::Vector3d& p2, double* t) noexcept {
  const Eigen::Vector3d e1 = p1 - p0, e2 = p2 - p0;
  const Eigen::Vector3d pv = d.cross(e2);
  const double det = e1.dot(pv);
  if (std::abs(det) < 1e-300) return false;
  const double inv = 1.0 / det;
  const Eigen::Vector3d tv = a - p0;
  const double u = tv.dot(pv) * inv;
  if (u < -kEdgeSlack || u > 1 + kEdgeSlack) return false;
  const Eigen::Vector3d qv = tv.cross(e1);
  const double v = d.dot(qv) * inv;
  if (v < -kEdgeSlack || u + v > 1 + kEdgeSlack) return false;
  *t = e2.dot(qv) * inv;
  return true;
}

}  // namespace

TriangleGrid::TriangleGrid(const Points3& vertices, const Faces3& faces, double cell_mm)
    : vertices_(vertices), faces_(faces), cell_mm_(cell_mm) {
  if (!(cell_mm > 0)) ThrowUsage("triangle grid: the cell must be > 0 mm");
  if (faces.rows() == 0) ThrowUsage("triangle grid: no triangles");
  normals_.resize(faces.rows(), 3);
  Bounds3 bounds;
  for (Eigen::Index f = 0; f < faces.rows(); ++f) {
    const Eigen::Vector3d a = vertices.row(faces(f, 0)), b = vertices.row(faces(f, 1)),
                          c = vertices.row(faces(f, 2));
    const Eigen::Vector3d n = (b - a).cross(c - a);
    const double len = n.norm();
    normals_.row(f) = len > 0 ? Eigen::Vector3d(n / len) : Eigen::Vector3d::Zero();
    for (const Eigen::Vector3d* q : {&a, &b, &c}) {
      bounds.min = bounds.min.cwiseMin(*q);
      bounds.max = bounds.max.cwiseMax(*q);
    }
  }
  origin_ = bounds.min.array() - cell_mm;
  const Eigen::Vector3d extent = bounds.max - origin_;
  for (int k = 0; k < 3; ++k) dims_(k) = std::max(1, static_cast<int>(std::ceil(extent(k) / cell_mm)) + 1);
  const std::size_t num_cells = static_cast<std::size_t>(dims_.prod());
  // Two passes (count, fill): compressed rows of face indices per cell.
  std::vector<std::int32_t> count(num_cells + 1, 0);
  auto for_face_cells = [&](Eigen::Index f, auto&& use) {
    Eigen::Vector3d lo = vertices.row(faces(f, 0)), hi = lo;
    for (int i = 1; i < 3; ++i) {
      lo = lo.cwiseMin(vertices.row(faces(f, i)).transpose());
      hi = hi.cwiseMax(vertices.row(faces(f, i)).transpose());
    }
    const Eigen::Vector3i c0 = CellOf(lo), c1 = CellOf(hi);
    for (int z = c0.z(); z <= c1.z(); ++z)
      for (int y = c0.y(); y <= c1.y(); ++y)
        for (int x = c0.x(); x <= c1.x(); ++x)
          use((static_cast<std::size_t>(z) * dims_.y() + y) * dims_.x() + x);
  };
  for (Eigen::Index f = 0; f < faces.rows(); ++f)
    for_face_cells(f, [&](std::size_t cell) { ++count[cell + 1]; });
  for (std::size_t i = 0; i < num_cells; ++i) count[i + 1] += count[i];
  cell_start_ = count;
  cell_faces_.resize(static_cast<std::size_t>(count.back()));
  for (Eigen::Index f = 0; f < faces.rows(); ++f) {
    for_face_cells(f, [&](std::size_t cell) {
      cell_faces_[static_cast<std::size_t>(count[cell]++)] = static_cast<std::int32_t>(f);
    });
  }
}

Eigen::Vector3i TriangleGrid::CellOf(const Eigen::Vector3d& p) const noexcept {
  Eigen::Vector3i c;
  for (int k = 0; k < 3; ++k) {
    const double x = std::floor((p(k) - origin_(k)) / cell_mm_);
    c(k) = static_cast<int>(std::clamp(x, 0.0, static_cast<double>(dims_(k) - 1)));
  }
  return c;
}

template <class Visit>
void TriangleGrid::ForCells(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi,
                            Visit&& visit) const noexcept {
  const Eigen::Vector3i c0 = CellOf(lo), c1 = CellOf(hi);
  for (int z = c0.z(); z <= c1.z(); ++z) {
    for (int y = c0.y(); y <= c1.y(); ++y) {
      for (int x = c0.x(); x <= c1.x(); ++x) {
        const std::size_t cell = (static_cast<std::size_t>(z) * dims_.y() + y) * dims_.x() + x;
        for (std::int32_t i = cell_start_[cell]; i < cell_start_[cell + 1]; ++i) {
          if (!visit(cell_faces_[static_cast<std::size_t>(i)])) return;
        }
      }
    }
  }
}

bool TriangleGrid::FirstHit(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const std::int32_t* ignore,
                            int num_ignore, SurfaceHit* hit) const noexcept {
  const Eigen::Vector3d d = b - a;
  double best = std::numeric_limits<double>::infinity();
  std::int32_t best_face = -1;
  ForCells(a.cwiseMin(b), a.cwiseMax(b), [&](std::int32_t f) {
    for (int i = 0; i < num_ignore; ++i) {
      if (ignore[i] == f) return true;
    }
    if (d.dot(normals_.row(f)) >= 0) return true;  // leaving or grazing: not a contact
    double t;
    if (LineTriangle(a, d, vertices_.row(faces_(f, 0)), vertices_.row(faces_(f, 1)),
                     vertices_.row(faces_(f, 2)), &t) &&
        t >= -1e-12 && t <= 1 && t < best) {
      best = t;
      best_face = f;
    }
    return true;
  });
  if (best_face < 0) return false;
  hit->t = std::max(0.0, best);
  hit->point = a + hit->t * d;
  hit->normal = normals_.row(best_face);
  hit->face = best_face;
  hit->distance_mm = hit->t * d.norm();
  return true;
}

bool TriangleGrid::Nearest(const Eigen::Vector3d& p, double radius_mm, SurfaceHit* hit) const noexcept {
  double best = radius_mm * radius_mm;
  std::int32_t best_face = -1;
  Eigen::Vector3d best_point = p;
  ForCells(p.array() - radius_mm, p.array() + radius_mm, [&](std::int32_t f) {
    const Eigen::Vector3d v0 = vertices_.row(faces_(f, 0));
    const double plane = normals_.row(f).dot(p - v0);
    if (plane * plane > best) return true;  // its plane alone is farther than the best so far
    const Eigen::Vector3d q = ClosestPointOnTriangle(
        p, vertices_.row(faces_(f, 0)), vertices_.row(faces_(f, 1)), vertices_.row(faces_(f, 2)));
    const double d2 = (q - p).squaredNorm();
    if (d2 <= best) {
      best = d2;
      best_face = f;
      best_point = q;
    }
    return true;
  });
  if (best_face < 0) return false;
  hit->point = best_point;
  hit->normal = normals_.row(best_face);
  hit->face = best_face;
  hit->distance_mm = std::sqrt(best);
  hit->t = 0;
  return true;
}

void TriangleGrid::AllHits(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                           std::vector<SurfaceHit>* hits) const {
  const Eigen::Vector3d d = b - a;
  std::vector<SurfaceHit> found;
  ForCells(a.cwiseMin(b), a.cwiseMax(b), [&](std::int32_t f) {
    double t;
    if (LineTriangle(a, d, vertices_.row(faces_(f, 0)), vertices_.row(faces_(f, 1)),
                     vertices_.row(faces_(f, 2)), &t) &&
        t >= 0 && t <= 1) {
      SurfaceHit h;
      h.t = t;
      h.point = a + t * d;
      h.normal = normals_.row(f);
      h.face = f;
      h.distance_mm = t * d.norm();
      found.push_back(h);
    }
    return true;
  });
  // A face binned in several cells is met once per cell: keep one.
  std::sort(found.begin(), found.end(),
            [](const SurfaceHit& x, const SurfaceHit& y) { return x.face < y.face; });
  found.erase(std::unique(found.begin(), found.end(),
                          [](const SurfaceHit& x, const SurfaceHit& y) { return x.face == y.face; }),
              found.end());
  std::sort(found.begin(), found.end(), [](const SurfaceHit& x, const SurfaceHit& y) { return x.t < y.t; });
  hits->insert(hits->end(), found.begin(), found.end());
}

}  // namespace pectus::trainer
