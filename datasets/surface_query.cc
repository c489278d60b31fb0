#include "datasets/surface_query.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <vector>

#include "shape/core/error.h"

namespace pectus::datasets {
namespace {

constexpr double kLo[2] = {kUMin, kVMin};
constexpr double kHi[2] = {kUMax, kVMax};

Eigen::Vector2d Clamp(const Eigen::Vector2d& uv) {
  return {std::clamp(uv.x(), kUMin, kUMax), std::clamp(uv.y(), kVMin, kVMax)};
}

}  // namespace

ClosestPointResult ClosestPoint(const ChestSurface& surface, const Eigen::Vector3d& query,
                                const ClosestPointOptions& options) {
  ClosestPointResult result;
  Eigen::Vector2d uv =
      options.initial_uv.allFinite() ? Clamp(options.initial_uv) : surface.GuessParameters(query);
  SurfacePoint sp = surface.Evaluate(uv.x(), uv.y());
  double cost = (sp.position - query).squaredNorm();
  bool fixed[2] = {false, false};
  for (result.iterations = 0; result.iterations < options.max_iterations; ++result.iterations) {
    Eigen::Matrix<double, 3, 2> J;
    J << sp.d_du, sp.d_dv;
    const Eigen::Vector3d r = sp.position - query;
    const Eigen::Vector2d g = J.transpose() * r;
    const Eigen::Matrix2d H = J.transpose() * J;
    // Active set: a parameter at a bound whose descent direction leaves the domain stays there.
    for (int k = 0; k < 2; ++k) {
      fixed[k] = (uv(k) <= kLo[k] && g(k) > 0.0) || (uv(k) >= kHi[k] && g(k) < 0.0);
    }
    Eigen::Vector2d step = Eigen::Vector2d::Zero();
    if (!fixed[0] && !fixed[1]) {
      step = -H.ldlt().solve(g);
    } else if (!fixed[0]) {
      step(0) = -g(0) / H(0, 0);
    } else if (!fixed[1]) {
      step(1) = -g(1) / H(1, 1);
    }
    // Near the minimum the full Gauss-Newton step contracts; farther off, backtracking keeps each step a
    // descent step. (Comparing costs cannot resolve steps under ~1e-7 mm, so small steps are taken as they
    // are.)
    const double predicted = (J * step).norm();
    Eigen::Vector2d next = Clamp(uv + step);
    SurfacePoint next_sp = surface.Evaluate(next.x(), next.y());
    double next_cost = (next_sp.position - query).squaredNorm();
    bool accepted = predicted < 1e-3 || next_cost <= cost;
    for (int halving = 0; halving < 40 && !accepted; ++halving) {
      step *= 0.5;
      next = Clamp(uv + step);
      next_sp = surface.Evaluate(next.x(), next.y());
      next_cost = (next_sp.position - query).squaredNorm();
      accepted = next_cost <= cost;
    }
    if (!accepted) {
      result.converged = true;  // no descent direction left: a (boundary) minimum
      break;
    }
    const double moved = (next_sp.position - sp.position).norm();
    uv = next;
    sp = next_sp;
    cost = next_cost;
    if (moved < options.tolerance_mm) {
      result.converged = true;
      break;
    }
  }
  result.uv = uv;
  result.point = sp.position;
  result.normal = sp.normal;
  const Eigen::Vector3d d = query - sp.position;
  result.distance = d.norm();
  result.signed_distance = d.dot(sp.normal) < 0.0 ? -result.distance : result.distance;
  result.on_boundary = uv.x() <= kUMin || uv.x() >= kUMax || uv.y() <= kVMin || uv.y() >= kVMax;
  return result;
}

double SignedDistance(const ChestSurface& surface, const Eigen::Vector3d& query) {
  return ClosestPoint(surface, query).signed_distance;
}

std::optional<RayHit> IntersectRay(const ChestSurface& surface, const Eigen::Vector3d& origin,
                                   const Eigen::Vector3d& direction, const Eigen::Vector2d& uv_guess) {
  Eigen::Vector3d x(uv_guess.x(), uv_guess.y(), 0.0);
  x.z() = (surface.Position(x.x(), x.y()) - origin).dot(direction);
  for (int iteration = 0; iteration < 40; ++iteration) {
    const SurfacePoint sp = surface.Evaluate(x.x(), x.y());
    const Eigen::Vector3d F = sp.position - origin - x.z() * direction;
    if (F.norm() < 1e-9) {
      if (x.z() <= 0.0 || x.x() < kUMin || x.x() > kUMax || x.y() < kVMin || x.y() > kVMax)
        return std::nullopt;
      return RayHit{x.head<2>(), x.z(), sp.position, sp.normal};
    }
    Eigen::Matrix3d J;
    J << sp.d_du, sp.d_dv, -direction;
    const Eigen::Vector3d step = J.partialPivLu().solve(-F);
    if (!step.allFinite()) return std::nullopt;
    // Limit a step in parameters to a fifth of the domain, so that Newton cannot jump to a far sheet.
    const double limit = std::max({std::abs(step.x()) / 0.4, std::abs(step.y()) / 0.2, 1.0});
    x += step / limit;
    if (std::abs(x.x()) > 1.6 || x.y() < -0.6 || x.y() > 1.6) return std::nullopt;
  }
  return std::nullopt;
}

TriangleMesh TessellateGrid(const ChestSurface& surface, int nu, int nv, double u0, double u1, double v0,
                            double v1) {
  if (nu < 2 || nv < 2) ThrowUsage("a surface grid needs at least 2 by 2 vertices");
  std::vector<double> us(nu), vs(nv);
  for (int i = 0; i < nu; ++i) us[i] = u0 + (u1 - u0) * i / (nu - 1);
  for (int j = 0; j < nv; ++j) vs[j] = v0 + (v1 - v0) * j / (nv - 1);
  return TessellateLines(surface, us, vs);
}

TriangleMesh TessellateLines(const ChestSurface& surface, const std::vector<double>& us,
                             const std::vector<double>& vs) {
  const int nu = static_cast<int>(us.size()), nv = static_cast<int>(vs.size());
  if (nu < 2 || nv < 2) ThrowUsage("a surface grid needs at least 2 by 2 vertices");
  TriangleMesh mesh;
  const Eigen::Index n = static_cast<Eigen::Index>(nu) * nv;
  mesh.vertices.positions.resize(n, 3);
  mesh.vertices.normals.resize(n, 3);
  Eigen::VectorXd u_values(n), v_values(n);
#pragma omp parallel for schedule(static)
  for (int j = 0; j < nv; ++j) {
    for (int i = 0; i < nu; ++i) {
      const SurfacePoint sp = surface.Evaluate(us[i], vs[j]);
      const Eigen::Index k = static_cast<Eigen::Index>(j) * nu + i;
      mesh.vertices.positions.row(k) = sp.position.transpose();
      mesh.vertices.normals.row(k) = sp.normal.transpose();
      u_values(k) = us[i];
      v_values(k) = vs[j];
    }
  }
  mesh.vertices.scalars["u"] = u_values;
  mesh.vertices.scalars["v"] = v_values;
  mesh.faces.resize(2 * static_cast<Eigen::Index>(nu - 1) * (nv - 1), 3);
  Eigen::Index f = 0;
  for (int j = 0; j + 1 < nv; ++j) {
    for (int i = 0; i + 1 < nu; ++i) {
      const int a = j * nu + i, b = a + 1, c = a + nu + 1, d = a + nu;
      mesh.faces.row(f++) << a, b, c;
      mesh.faces.row(f++) << a, c, d;
    }
  }
  return mesh;
}

namespace {

// Parameter values from lo to hi whose steps each cover about `spacing` of the integral of `speed` (sampled
// at equal steps over [lo, hi]): where the surface moves fast, the lines crowd.
std::vector<double> EqualArcLines(const std::vector<double>& speed, double lo, double hi, double spacing) {
  const int m = static_cast<int>(speed.size());
  const double h = (hi - lo) / (m - 1);
  std::vector<double> cumulative(m, 0.0);
  for (int k = 1; k < m; ++k) cumulative[k] = cumulative[k - 1] + 0.5 * (speed[k - 1] + speed[k]) * h;
  const int intervals = std::max(1, static_cast<int>(std::ceil(cumulative.back() / spacing)));
  std::vector<double> lines(intervals + 1);
  int k = 0;
  for (int i = 0; i <= intervals; ++i) {
    const double target = cumulative.back() * i / intervals;
    while (k + 2 < m && cumulative[k + 1] < target) ++k;
    const double span = cumulative[k + 1] - cumulative[k];
    const double t = span > 0.0 ? std::clamp((target - cumulative[k]) / span, 0.0, 1.0) : 0.0;
    lines[i] = lo + (k + t) * h;
  }
  lines.front() = lo;
  lines.back() = hi;
  return lines;
}

}  // namespace

TriangleMesh Tessellate(const ChestSurface& surface, double spacing_mm) {
  if (!(spacing_mm > 0.05)) ThrowUsage("tessellation spacing must be over 0.05 mm");
  // The fastest the surface moves per unit u at each u (over all v), and per unit v at each v, sampled on a
  // 201 by 201 grid (2 % margin for what falls between samples).
  const int samples = 201;
  std::vector<double> speed_u(samples, 0.0), speed_v(samples, 0.0);
  for (int j = 0; j < samples; ++j) {
    for (int i = 0; i < samples; ++i) {
      const SurfacePoint sp = surface.Evaluate(kUMin + (kUMax - kUMin) * i / (samples - 1),
                                               kVMin + (kVMax - kVMin) * j / (samples - 1));
      speed_u[i] = std::max(speed_u[i], 1.02 * sp.d_du.norm());
      speed_v[j] = std::max(speed_v[j], 1.02 * sp.d_dv.norm());
    }
  }
  return TessellateLines(surface, EqualArcLines(speed_u, kUMin, kUMax, spacing_mm),
                         EqualArcLines(speed_v, kVMin, kVMax, spacing_mm));
}

}  // namespace pectus::datasets
