// pectus datasets (internal): where each sweep of a scan goes over the chest's (u, v) domain, and the walk
// of the wand along it, one laser line at a time (docs/datasets.md, "The scan").
#pragma once

#include <Eigen/Core>
#include <random>
#include <vector>

#include "datasets/scan_simulator.h"

namespace pectus::datasets::internal {

/// One sweep's nominal path over the (u, v) domain.
///  - straight (vertical and horizontal strips, patches): the wand moves along the axis `axis` (0: u,
///    1: v) in the direction `sign` from `begin` to `end`, at the middle of [lo, hi] on the other axis;
///    its laser line spans [lo, hi] on that axis;
///  - spiral: the wand follows q(theta) = r(theta) (cos theta, sin theta), r = r_in + pitch theta / 2 pi,
///    theta in [begin, end], in coordinates q = ((u - centre_u) / radius_u, (v - centre_v) / radius_v);
///    its laser line runs radially, `half` (q units) either side.
struct SweepPlan {
  bool spiral = false;
  int axis = 1;                   ///< straight: the axis the wand moves along
  int sign = -1;                  ///< straight: +1 toward larger values, -1 toward smaller ones
  double begin = 0.0, end = 0.0;  ///< along the axis (straight) or theta (spiral, radians)
  double lo = 0.0, hi = 0.0;      ///< straight: the laser line's extent on the other axis
  double centre_u = 0.0, centre_v = 0.0, radius_u = 1.0, radius_v = 1.0;  ///< spiral: its frame
  double r_in = 0.0, pitch = 0.0, half = 0.0;                             ///< spiral: radii (q units)
  double u0 = -1.0, u1 = 1.0, v0 = 0.0, v1 = 1.0;  ///< nominal extent (holes are drawn in it; the truth)
  double hole_v0 = 0.05, hole_v1 = 0.95;           ///< the sweep's holes are drawn within u0..u1 and these
};

/// The plans of options.sweeps sweeps in options.pattern, neighbours sharing options.overlap.
std::vector<SweepPlan> PlanSweeps(const ScanOptions& options);

/// The wand's walk along a plan: the path point of the current laser line, the path's direction and the
/// laser line's direction and half-length there (all in (u, v)); ragged ends drawn on construction.
class SweepWalk {
 public:
  /// Draws the ragged start and end (two uniform draws from `rng`, start first).
  SweepWalk(const SweepPlan& plan, std::mt19937_64* rng);
  bool Running() const;
  /// Moves the wand on by `step` path units (clamped to MaxStep()).
  void Advance(double step);
  /// The path point (may lie outside the domain at the ragged ends or beyond the chest).
  Eigen::Vector2d Centre() const;
  /// d Centre / d path unit (the direction the wand moves in).
  Eigen::Vector2d Along() const;
  /// The laser line's direction in (u, v), scaled so that Half() of it is half the line.
  Eigen::Vector2d Across() const;
  double Half() const;
  /// The longest step per line in path units (a spiral's turns near the centre are short).
  double MaxStep() const;
  bool Straight() const { return !plan_.spiral; }

 private:
  const SweepPlan& plan_;
  double x_ = 0.0, end_ = 0.0;
};

}  // namespace pectus::datasets::internal
