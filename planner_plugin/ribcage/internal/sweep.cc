#include "planner_plugin/ribcage/internal/sweep.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

#include "shape/core/error.h"

namespace pectus::planner {

std::vector<Eigen::Vector3d> SweepPositions(const std::vector<SweepStation>& stations, int nu, int nv,
                                            const std::vector<Eigen::Vector3d>* end_window,
                                            int blend_stations) {
  const int n = static_cast<int>(stations.size());
  if (n < 2 || nu < 1 || nv < 1 || blend_stations < 1) ThrowFailure("sweep: too few stations or cells");
  const std::size_t per_station = static_cast<std::size_t>(nu + 1) * (nv + 1);
  if (end_window != nullptr && end_window->size() != per_station) {
    ThrowFailure("sweep: the end window has " + std::to_string(end_window->size()) + " nodes, expected " +
                 std::to_string(per_station));
  }
  std::vector<Eigen::Vector3d> positions(per_station * static_cast<std::size_t>(n));
  for (int s = 0; s < n; ++s) {
    const SweepStation& st = stations[s];
    for (int iu = 0; iu <= nu; ++iu) {
      for (int iv = 0; iv <= nv; ++iv) {
        positions[(static_cast<std::size_t>(s) * (nu + 1) + iu) * (nv + 1) + iv] =
            st.centre + (static_cast<double>(iu) / nu - 0.5) * st.height * st.up +
            (static_cast<double>(iv) / nv - 0.5) * st.thickness * st.out;
      }
    }
  }
  if (end_window != nullptr) {
    const std::size_t last = per_station * static_cast<std::size_t>(n - 1);
    const int k = std::min(blend_stations, n - 1);
    for (std::size_t q = 0; q < per_station; ++q) {
      const Eigen::Vector3d delta = (*end_window)[q] - positions[last + q];
      for (int j = 1; j <= k; ++j) {
        // Station n - 1 - k + j gets weight smoothstep(j / k): 1 at the end.
        const double t = static_cast<double>(j) / k, w = t * t * (3 - 2 * t);
        positions[per_station * static_cast<std::size_t>(n - 1 - k + j) + q] += w * delta;
      }
      positions[last + q] = (*end_window)[q];
    }
  }
  return positions;
}

double PolylineLength(const std::vector<Eigen::Vector3d>& polyline) {
  double length = 0.0;
  for (std::size_t i = 1; i < polyline.size(); ++i) length += (polyline[i] - polyline[i - 1]).norm();
  return length;
}

std::vector<Eigen::Vector3d> ResampleByArcLength(const std::vector<Eigen::Vector3d>& polyline, int segments) {
  if (polyline.size() < 2 || segments < 1) ThrowFailure("resample: need a polyline and at least one segment");
  std::vector<double> cumulative(polyline.size(), 0.0);
  for (std::size_t i = 1; i < polyline.size(); ++i) {
    cumulative[i] = cumulative[i - 1] + (polyline[i] - polyline[i - 1]).norm();
  }
  std::vector<Eigen::Vector3d> out;
  out.reserve(static_cast<std::size_t>(segments) + 1);
  std::size_t i = 1;
  for (int k = 0; k <= segments; ++k) {
    const double target = cumulative.back() * k / segments;
    while (i + 1 < polyline.size() && cumulative[i] < target) ++i;
    const double span = cumulative[i] - cumulative[i - 1];
    const double t = span > 0 ? std::clamp((target - cumulative[i - 1]) / span, 0.0, 1.0) : 0.0;
    out.push_back((1 - t) * polyline[i - 1] + t * polyline[i]);
  }
  out.front() = polyline.front();
  out.back() = polyline.back();
  return out;
}

std::vector<Eigen::Vector3d> HermiteCurve(const Eigen::Vector3d& p0, const Eigen::Vector3d& t0,
                                          const Eigen::Vector3d& p1, const Eigen::Vector3d& t1, int samples) {
  std::vector<Eigen::Vector3d> out;
  for (int k = 0; k <= samples; ++k) {
    const double s = static_cast<double>(k) / samples;
    const double h00 = 2 * s * s * s - 3 * s * s + 1, h10 = s * s * s - 2 * s * s + s;
    const double h01 = -2 * s * s * s + 3 * s * s, h11 = s * s * s - s * s;
    out.push_back(h00 * p0 + h10 * t0 + h01 * p1 + h11 * t1);
  }
  return out;
}

}  // namespace pectus::planner
