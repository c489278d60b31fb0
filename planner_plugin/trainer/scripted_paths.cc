#include "planner_plugin/trainer/scripted_paths.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "shape/core/error.h"

namespace pectus::trainer {
namespace {

constexpr double kPi = 3.14159265358979323846;

// The middle of the tunnel: 1 where |x| is within 35 % of the port's, falling as cos^2 to 0 at 70 %.
double MiddleWeight(double x, double port_x) {
  const double u = std::abs(x / port_x);
  if (u <= 0.35) return 1;
  if (u >= 0.7) return 0;
  const double c = std::cos(0.5 * kPi * (u - 0.35) / 0.35);
  return c * c;
}

}  // namespace

const char* PathKindName(PathKind kind) {
  switch (kind) {
    case PathKind::kExpert: return "expert";
    case PathKind::kTooDeep: return "too deep";
    case PathKind::kOntoPericardium: return "onto the pericardium";
    case PathKind::kWrongSpace: return "wrong space";
  }
  return "?";
}

bool ScriptedPathOptions::IsValid(std::string* why) const {
  const bool ok = speed_mm_s > 0 && wobble_mm >= 0 && outside_mm >= 0 && sample_s > 0 &&
                  too_deep_clearance_mm >= 0 && onto_pericardium_mm >= 0 && std::isfinite(wobble_phase_rad);
  if (!ok && why != nullptr) *why = "scripted path: speed and sample step must be > 0, lengths >= 0";
  return ok;
}

Trajectory MakeScriptedPath(const TrainerScene& scene, const ScriptedPathOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) ThrowUsage(why);
  const PlannedTunnel& tunnel = scene.tunnel;
  auto outward = [&](const Eigen::Vector3d& port) {
    return Eigen::Vector3d(port.x(), port.y() - scene.chest_axis_y_mm, 0).normalized();
  };
  // The wrong space: the one above the planned entry (or below if there is none).
  Eigen::Vector3d entry_shift = Eigen::Vector3d::Zero();
  if (options.kind == PathKind::kWrongSpace) {
    bool found = false;
    for (int step : {-1, 1}) {
      for (const auto& [space, centre] : scene.ports) {
        if (!found && space.side == tunnel.entry.side && space.number == tunnel.entry.number + step) {
          entry_shift = centre - tunnel.entry_port;
          found = true;
        }
      }
    }
    if (!found) ThrowFailure("scripted path: no intercostal space beside the planned one");
  }
  // A deeper path: each point of the tunnel's middle moves towards its nearest point of the pericardium,
  // by as much as brings the tunnel's nearest approach to the wanted clearance (negative: into it).
  const bool deeper = options.kind == PathKind::kTooDeep || options.kind == PathKind::kOntoPericardium;
  const double clearance =
      options.kind == PathKind::kTooDeep ? options.too_deep_clearance_mm : -options.onto_pericardium_mm;
  auto middle = [&](const Eigen::Vector3d& p) {
    return MiddleWeight(p.x(), p.x() < 0 ? tunnel.entry_port.x() : tunnel.exit_port.x());
  };
  double nearest_approach = std::numeric_limits<double>::infinity();
  for (Eigen::Index i = 0; i < tunnel.points.rows() && deeper; ++i) {
    const Eigen::Vector3d p = tunnel.points.row(i).transpose();
    if (middle(p) == 1) nearest_approach = std::min(nearest_approach, scene.DistanceToPericardium(p));
  }
  // The path's knots: outside the right port, the tunnel (changed by the kind), outside the left port.
  std::vector<Eigen::Vector3d> knots;
  knots.push_back(tunnel.entry_port + entry_shift + options.outside_mm * outward(tunnel.entry_port));
  for (Eigen::Index i = 0; i < tunnel.points.rows(); ++i) {
    Eigen::Vector3d p = tunnel.points.row(i).transpose();
    SurfaceHit nearest;
    if (deeper && std::isfinite(nearest_approach) && scene.pericardium_grid.Nearest(p, 400, &nearest) &&
        nearest.distance_mm > 0) {
      p += (nearest_approach - clearance) * middle(p) * (nearest.point - p) / nearest.distance_mm;
    }
    if (options.kind == PathKind::kWrongSpace && p.x() < 0) {
      p += std::clamp(p.x() / tunnel.entry_port.x(), 0.0, 1.0) * entry_shift;
    }
    knots.push_back(p);
  }
  knots.push_back(tunnel.exit_port + options.outside_mm * outward(tunnel.exit_port));
  std::vector<double> arc(knots.size(), 0.0);
  for (std::size_t i = 1; i < knots.size(); ++i) arc[i] = arc[i - 1] + (knots[i] - knots[i - 1]).norm();
  // Walked at the speed, with the hand's wobble across the path.
  Trajectory out;
  const double duration = arc.back() / options.speed_mm_s;
  const auto n = static_cast<std::size_t>(std::ceil(duration / options.sample_s)) + 1;
  std::size_t segment = 0;
  for (std::size_t k = 0; k < n; ++k) {
    const double t = static_cast<double>(k) * options.sample_s;
    const double s = std::min(arc.back(), options.speed_mm_s * t);
    while (segment + 2 < knots.size() && arc[segment + 1] < s) ++segment;
    const double len = arc[segment + 1] - arc[segment];
    const double w = len > 0 ? (s - arc[segment]) / len : 0.0;
    const Eigen::Vector3d tangent = (knots[segment + 1] - knots[segment]).normalized();
    const Eigen::Vector3d side = tangent.cross(Eigen::Vector3d::UnitZ()).normalized();
    const double phase = options.wobble_phase_rad;
    DeviceState state;
    state.time_s = t;
    state.position_mm = knots[segment] + w * (knots[segment + 1] - knots[segment]) +
                        options.wobble_mm * (std::sin(2 * kPi * 0.7 * t + phase) * Eigen::Vector3d::UnitZ() +
                                             std::sin(2 * kPi * 1.3 * t + 2 * phase) * side);
    state.orientation = Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitZ(), tangent);
    out.samples.push_back(state);
  }
  for (std::size_t i = 0; i < out.samples.size(); ++i) {
    const DeviceState& a = out.samples[i == 0 ? 0 : i - 1];
    const DeviceState& b = out.samples[std::min(i + 1, out.samples.size() - 1)];
    if (b.time_s > a.time_s)
      out.samples[i].velocity_mm_s = (b.position_mm - a.position_mm) / (b.time_s - a.time_s);
  }
  return out;
}

}  // namespace pectus::trainer
