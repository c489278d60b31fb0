// pectus datasets: exact queries on a ChestSurface — closest point, signed distance, ray intersection,
// tessellation. The truth that later stages are measured against.
#pragma once

#include <Eigen/Core>
#include <optional>
#include <vector>

#include "datasets/chest_surface.h"
#include "shape/core/geometry.h"

namespace pectus::datasets {

/// Options for ClosestPoint.
struct ClosestPointOptions {
  int max_iterations = 200;     ///< Gauss-Newton iterations at most
  double tolerance_mm = 1e-10;  ///< stop when the step moves the foot point less than this, mm
  /// Starting parameters; NaN: ChestSurface::GuessParameters.
  Eigen::Vector2d initial_uv = Eigen::Vector2d::Constant(std::numeric_limits<double>::quiet_NaN());
};

/// The nearest point of the bounded surface patch to a query point.
struct ClosestPointResult {
  Eigen::Vector2d uv = Eigen::Vector2d::Zero();      ///< parameters of the foot point
  Eigen::Vector3d point = Eigen::Vector3d::Zero();   ///< foot point, mm
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();  ///< unit outward normal at the foot point
  double distance = 0.0;                             ///< |query - point|, mm
  double signed_distance = 0.0;  ///< distance, negative below the surface (against the normal), mm
  bool on_boundary = false;      ///< the foot point lies on the border of the domain
  bool converged = false;
  int iterations = 0;
};

/// Closest point by projected Gauss-Newton on |x(u, v) - query|^2 over the domain [-1, 1] x [0, 1]: the
/// foot point is exact to `tolerance_mm` (1e-10 mm by default). It is the global closest point for queries
/// nearer the surface than its smallest radius of curvature (over 5 mm for every generated chest), and a
/// local one for queries farther off.
/// @param[in] surface  the subject's surface
/// @param[in] query    a point, mm, scan frame
ClosestPointResult ClosestPoint(const ChestSurface& surface, const Eigen::Vector3d& query,
                                const ClosestPointOptions& options = {});

/// Signed distance to the surface patch (ClosestPoint(...).signed_distance), mm.
double SignedDistance(const ChestSurface& surface, const Eigen::Vector3d& query);

/// Where a ray meets the surface.
struct RayHit {
  Eigen::Vector2d uv;      ///< parameters of the hit
  double t = 0.0;          ///< distance along the (unit) ray, mm
  Eigen::Vector3d point;   ///< mm, scan frame
  Eigen::Vector3d normal;  ///< unit outward normal at the hit
};

/// Intersects the ray origin + t direction (t > 0) with the surface by Newton's method on (u, v, t),
/// started from `uv_guess` (and t from the projection of that point on the ray). Exact to 1e-9 mm.
/// @return the hit, or nothing if Newton does not converge or the hit lies outside the domain
std::optional<RayHit> IntersectRay(const ChestSurface& surface, const Eigen::Vector3d& origin,
                                   const Eigen::Vector3d& direction, const Eigen::Vector2d& uv_guess);

/// A grid mesh of the surface: nu by nv vertices over [u0, u1] x [v0, v1], row-major in u (vertex
/// index = j * nu + i for u index i and v index j), triangles counter-clockwise seen from outside, exact
/// unit normals, and scalars "u" and "v" per vertex.
TriangleMesh TessellateGrid(const ChestSurface& surface, int nu, int nv, double u0 = kUMin, double u1 = kUMax,
                            double v0 = kVMin, double v1 = kVMax);

/// The same with the grid lines at the given parameter values (each list ascending, at least 2).
TriangleMesh TessellateLines(const ChestSurface& surface, const std::vector<double>& us,
                             const std::vector<double>& vs);

/// A grid mesh of the whole domain whose grid edges are at most about `spacing_mm` long: the u lines are
/// spaced by the largest speed |dx/du| over v at each u, the v lines likewise, so lines crowd only where the
/// surface moves fast (a depression's walls). Sampled on a 201 by 201 grid.
TriangleMesh Tessellate(const ChestSurface& surface, double spacing_mm);

}  // namespace pectus::datasets
