#include "datasets/chest_measurement.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "datasets/chest_landmarks.h"
#include "shape/core/error.h"

namespace pectus::datasets {
namespace {

// Golden-section search for the maximum of f on [lo, hi].
template <typename F>
double ArgMax(F f, double lo, double hi, int iterations = 50) {
  const double r = (std::sqrt(5.0) - 1.0) / 2.0;
  double a = hi - r * (hi - lo), b = lo + r * (hi - lo);
  double fa = f(a), fb = f(b);
  for (int i = 0; i < iterations; ++i) {
    if (fa > fb) {
      hi = b, b = a, fb = fa;
      a = hi - r * (hi - lo), fa = f(a);
    } else {
      lo = a, a = b, fa = fb;
      b = lo + r * (hi - lo), fb = f(b);
    }
  }
  return 0.5 * (lo + hi);
}

struct Slice {
  double width = 0.0, front_y = 0.0, depression = 0.0;
  Eigen::Vector2d deepest = Eigen::Vector2d::Zero();
};

double Cross(const Eigen::Vector2d& o, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  return (a.x() - o.x()) * (b.y() - o.y()) - (a.y() - o.y()) * (b.x() - o.x());
}

Slice MeasureSlice(const ChestSurface& surface, double v, int n, double central_fraction) {
  const Eigen::Vector3d g = surface.parameters().growth;
  auto at = [&](double u) -> Eigen::Vector2d {
    // (lateral, posterior) coordinates of the axial slice: y below grows toward the back.
    const Eigen::Vector3d p = surface.SubjectPosition(std::clamp(u, kUMin, kUMax), v).cwiseProduct(g);
    return {p.x(), -p.z()};
  };
  const double du = (kUMax - kUMin) / (n - 1);
  std::vector<Eigen::Vector2d> pts(n);
  for (int i = 0; i < n; ++i) pts[i] = at(kUMin + i * du);
  auto best = [&](auto score) {
    int k = 0;
    for (int i = 1; i < n; ++i) {
      if (score(pts[i]) > score(pts[k])) k = i;
    }
    const double u = ArgMax([&](double t) { return score(at(t)); }, std::max(kUMin, kUMin + (k - 1) * du),
                            std::min(kUMax, kUMin + (k + 1) * du));
    return at(u);
  };
  Slice s;
  s.width = best([](const Eigen::Vector2d& p) { return p.x(); }).x() -
            best([](const Eigen::Vector2d& p) { return -p.x(); }).x();
  s.front_y = best([](const Eigen::Vector2d& p) { return -p.y(); }).y();
  // Anterior convex hull (the chain of smallest y) by Andrew's monotone chain on points sorted by x.
  std::vector<int> order(n);
  for (int i = 0; i < n; ++i) order[i] = i;
  std::sort(order.begin(), order.end(), [&](int a, int b) { return pts[a].x() < pts[b].x(); });
  std::vector<int> hull;
  for (int i : order) {
    while (hull.size() >= 2 && Cross(pts[hull[hull.size() - 2]], pts[hull.back()], pts[i]) <= 0.0)
      hull.pop_back();
    hull.push_back(i);
  }
  // Distance behind the hull of a point at lateral position x and depth y (hull linear between vertices).
  auto gap = [&](const Eigen::Vector2d& q) {
    std::size_t h = 0;
    while (h + 2 < hull.size() && pts[hull[h + 1]].x() <= q.x()) ++h;
    const Eigen::Vector2d& a = pts[hull[h]];
    const Eigen::Vector2d& b = pts[hull[std::min(h + 1, hull.size() - 1)]];
    const double t = b.x() > a.x() ? (q.x() - a.x()) / (b.x() - a.x()) : 0.0;
    return q.y() - (a.y() + t * (b.y() - a.y()));
  };
  // The deepest point of the concavity: the farthest behind the hull (where a ruler laid across the chest
  // is farthest from it), searched over the front of the chest only (|x| <= central_fraction W / 2), so that
  // a dip beside a pectoral or breast bulge toward the flank does not count.
  const double x_limit = central_fraction * 0.5 * s.width;
  int deepest = 0;
  double deepest_gap = -1.0;
  for (int i = 0; i < n; ++i) {
    if (std::abs(pts[i].x()) > x_limit) continue;
    const double d = gap(pts[i]);
    if (d > deepest_gap) deepest = i, deepest_gap = d;
  }
  if (deepest_gap <= 1e-6) return s;
  const double u = ArgMax([&](double t) { return gap(at(t)); }, std::max(kUMin, kUMin + (deepest - 1) * du),
                          std::min(kUMax, kUMin + (deepest + 1) * du));
  s.deepest = at(u);
  s.depression = std::max(0.0, s.deepest.y() - s.front_y);
  return s;
}

}  // namespace

ChestMeasurement MeasureChest(const ChestSurface& surface, const MeasureOptions& options) {
  if (options.samples_across < 11 || options.slices < 3)
    ThrowUsage("measurement needs >= 11 samples and >= 3 slices");
  const double v_lo = formula::kVReference + (formula::kSXiphoid + options.margin_below) * formula::kSpan;
  const double v_hi = formula::kVReference + (formula::kSNotch - options.margin_above) * formula::kSpan;
  if (!(v_lo < v_hi)) ThrowUsage("measurement margins leave no slice to search");
  const double dv = (v_hi - v_lo) / (options.slices - 1);
  int best = -1;
  double best_depression = 0.0;
  for (int k = 0; k < options.slices; ++k) {
    const double d =
        MeasureSlice(surface, v_lo + k * dv, options.samples_across, options.central_fraction).depression;
    if (d > best_depression + 1e-9) best = k, best_depression = d;
  }
  double v = kVReference;
  if (best >= 0 && best_depression >= options.min_depression_mm) {
    v = ArgMax(
        [&](double t) {
          return MeasureSlice(surface, t, options.samples_across, options.central_fraction).depression;
        },
        std::max(v_lo, v_lo + (best - 1) * dv), std::min(v_hi, v_lo + (best + 1) * dv), 30);
  }
  const Slice s = MeasureSlice(surface, v, options.samples_across, options.central_fraction);
  const ChestParameters& p = surface.parameters();
  ChestMeasurement m;
  m.width_mm = s.width;
  m.depth_mm = 0.5 * p.depth_mm * p.growth.z() - s.front_y;
  m.depression_mm = s.depression;
  m.deepest_xz = {s.deepest.x(), -s.deepest.y()};
  m.slice_v = v;
  m.slice_y_mm = surface.SubjectPosition(0.0, v).y() * p.growth.y();
  const LandmarkDefinition& notch = FindLandmarkDefinition("sternal_notch");
  const LandmarkDefinition& xiphoid = FindLandmarkDefinition("xiphoid");
  m.sternal_length_mm =
      (surface.SubjectPosition(notch.u, notch.v).y() - surface.SubjectPosition(xiphoid.u, xiphoid.v).y()) *
      p.growth.y();
  return m;
}

}  // namespace pectus::datasets
