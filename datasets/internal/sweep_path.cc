#include "datasets/internal/sweep_path.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

namespace pectus::datasets::internal {
namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;

// `count` intervals of equal length covering [lo, hi], neighbours sharing `overlap` of a length.
std::vector<std::pair<double, double>> Tile(int count, double lo, double hi, double overlap) {
  const double width = (hi - lo) / (count - (count - 1) * overlap);
  std::vector<std::pair<double, double>> tiles(static_cast<std::size_t>(count));
  for (int j = 0; j < count; ++j) {
    const double a = lo + j * width * (1.0 - overlap);
    tiles[static_cast<std::size_t>(j)] = {a, std::min(hi, a + width)};
  }
  return tiles;
}

// A vertical strip or patch: u in [u0, u1], swept from v1 down to v0.
SweepPlan Vertical(double u0, double u1, double v0, double v1) {
  SweepPlan p;
  p.axis = 1;
  p.sign = -1;
  p.begin = v1;
  p.end = v0;
  p.lo = p.u0 = u0;
  p.hi = p.u1 = u1;
  p.v0 = v0;
  p.v1 = v1;
  p.hole_v0 = std::max(v0, 0.05);
  p.hole_v1 = std::min(v1, 0.95);
  return p;
}

}  // namespace

std::vector<SweepPlan> PlanSweeps(const ScanOptions& o) {
  const int n = o.sweeps;
  std::vector<SweepPlan> plans;
  switch (o.pattern) {
    case SweepPattern::kVertical:
      for (const auto& [u0, u1] : Tile(n, kUMin, kUMax, o.overlap))
        plans.push_back(Vertical(u0, u1, kVMin, kVMax));
      break;
    case SweepPattern::kHorizontal: {
      // Bands from the top down; the wand goes across the chest, every other band back the other way.
      auto bands = Tile(n, kVMin, kVMax, o.overlap);
      std::reverse(bands.begin(), bands.end());
      for (int j = 0; j < n; ++j) {
        SweepPlan p;
        p.axis = 0;
        p.sign = j % 2 ? -1 : 1;
        p.begin = p.sign > 0 ? kUMin : kUMax;
        p.end = p.sign > 0 ? kUMax : kUMin;
        p.lo = p.v0 = p.hole_v0 = bands[static_cast<std::size_t>(j)].first;
        p.hi = p.v1 = p.hole_v1 = bands[static_cast<std::size_t>(j)].second;
        p.u0 = -0.9;
        p.u1 = 0.9;
        plans.push_back(p);
      }
      break;
    }
    case SweepPattern::kPatches: {
      // Rows from the top down, each tiled into columns like vertical strips.
      const int rows = n <= 3 ? 1 : (n <= 8 ? 2 : 3);
      auto row_bands = Tile(rows, kVMin, kVMax, o.overlap);
      std::reverse(row_bands.begin(), row_bands.end());
      for (int r = 0; r < rows; ++r) {
        const int columns = n / rows + (r < n % rows ? 1 : 0);
        const auto [v0, v1] = row_bands[static_cast<std::size_t>(r)];
        for (const auto& [u0, u1] : Tile(columns, kUMin, kUMax, o.overlap))
          plans.push_back(Vertical(u0, u1, v0, v1));
      }
      break;
    }
    case SweepPattern::kSpiral: {
      // An ellipse of semi-axes 1.1 (u) and 0.55 (v) about mid-sternum is covered by n turns of a band of
      // width b whose successive turns share `overlap` of it: the pitch is b (1 - overlap), the first turn
      // starts b overlap / 2 from the centre (so the centre is covered) and the last ends at radius 1.
      const double b = 1.0 / (0.5 + 0.5 * o.overlap + n * (1.0 - o.overlap));
      for (int k = 0; k < n; ++k) {
        SweepPlan p;
        p.spiral = true;
        p.begin = kTwoPi * k;
        p.end = kTwoPi * (k + 1);
        p.centre_u = 0.0;
        p.centre_v = 0.575;  // mid-sternum: halfway between the xiphoid (0.25) and the notch (0.90)
        p.radius_u = 1.1;
        p.radius_v = 0.55;
        p.r_in = 0.5 * b * o.overlap;
        p.pitch = b * (1.0 - o.overlap);
        p.half = 0.5 * b;
        const double outer = p.r_in + (k + 1) * p.pitch + p.half;
        p.u0 = std::max(kUMin, p.centre_u - outer * p.radius_u);
        p.u1 = std::min(kUMax, p.centre_u + outer * p.radius_u);
        p.v0 = p.hole_v0 = std::max(kVMin, p.centre_v - outer * p.radius_v);
        p.v1 = p.hole_v1 = std::min(kVMax, p.centre_v + outer * p.radius_v);
        plans.push_back(p);
      }
      break;
    }
  }
  return plans;
}

SweepWalk::SweepWalk(const SweepPlan& plan, std::mt19937_64* rng) : plan_(plan) {
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  if (plan.spiral) {
    // Turns start and end within 0.05 rad of their nominal angle.
    x_ = plan.begin - 0.05 + 0.1 * uniform(*rng);
    end_ = plan.end - 0.05 + 0.1 * uniform(*rng);
  } else if (plan.sign < 0) {
    // The wand starts a little before the start and stops a little after the end (ragged ends).
    x_ = plan.begin + 0.02 - 0.04 * uniform(*rng);
    end_ = plan.end - 0.02 + 0.04 * uniform(*rng);
  } else {
    x_ = plan.begin - 0.02 + 0.04 * uniform(*rng);
    end_ = plan.end + 0.02 - 0.04 * uniform(*rng);
  }
}

bool SweepWalk::Running() const { return (plan_.spiral || plan_.sign > 0) ? x_ < end_ : x_ > end_; }

void SweepWalk::Advance(double step) {
  step = std::min(step, MaxStep());
  if (!plan_.spiral && plan_.sign < 0) {
    x_ -= step;
  } else {
    x_ += step;
  }
}

Eigen::Vector2d SweepWalk::Centre() const {
  if (plan_.spiral) {
    const double r = plan_.r_in + plan_.pitch * x_ / kTwoPi;
    return {plan_.centre_u + plan_.radius_u * r * std::cos(x_),
            plan_.centre_v + plan_.radius_v * r * std::sin(x_)};
  }
  const double middle = 0.5 * (plan_.lo + plan_.hi);
  return plan_.axis == 1 ? Eigen::Vector2d(middle, x_) : Eigen::Vector2d(x_, middle);
}

Eigen::Vector2d SweepWalk::Along() const {
  if (plan_.spiral) {
    const double r = plan_.r_in + plan_.pitch * x_ / kTwoPi, dr = plan_.pitch / kTwoPi;
    const double c = std::cos(x_), s = std::sin(x_);
    return {plan_.radius_u * (dr * c - r * s), plan_.radius_v * (dr * s + r * c)};
  }
  const double sign = plan_.sign;
  return plan_.axis == 1 ? Eigen::Vector2d(0.0, sign) : Eigen::Vector2d(sign, 0.0);
}

Eigen::Vector2d SweepWalk::Across() const {
  if (plan_.spiral) return {plan_.radius_u * std::cos(x_), plan_.radius_v * std::sin(x_)};
  return plan_.axis == 1 ? Eigen::Vector2d(1.0, 0.0) : Eigen::Vector2d(0.0, 1.0);
}

double SweepWalk::Half() const { return plan_.spiral ? plan_.half : 0.5 * (plan_.hi - plan_.lo); }

double SweepWalk::MaxStep() const { return plan_.spiral ? 0.02 : std::numeric_limits<double>::infinity(); }

}  // namespace pectus::datasets::internal
