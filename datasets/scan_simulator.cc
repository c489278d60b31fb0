#include "datasets/scan_simulator.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>

#include "datasets/internal/sweep_path.h"
#include "datasets/internal/tracker_error.h"
#include "datasets/internal/validation.h"
#include "datasets/seeding.h"
#include "datasets/surface_query.h"
#include "shape/core/enum_names.h"
#include "shape/core/error.h"
#include "shape/core/geometry.h"

namespace pectus::datasets {
namespace {

using internal::InRange;

// A smooth random wander in [-1, 1] along the laser-line index: three sines of random period and phase.
class Wander {
 public:
  Wander(std::mt19937_64* rng, double min_period, double max_period) {
    std::uniform_real_distribution<double> period(min_period, max_period), phase(0.0, 2.0 * std::numbers::pi);
    for (int i = 0; i < 3; ++i) {
      omega_[i] = 2.0 * std::numbers::pi / period(*rng);
      phase_[i] = phase(*rng);
    }
  }
  double operator()(double k) const {
    return 0.5 * std::sin(omega_[0] * k + phase_[0]) + 0.3 * std::sin(omega_[1] * k + phase_[1]) +
           0.2 * std::sin(omega_[2] * k + phase_[2]);
  }

 private:
  double omega_[3], phase_[3];
};

ScanHole MakeHole(const ChestSurface& surface, std::mt19937_64* rng, const ScanOptions& o, double u0,
                  double u1, double v0, double v1, int sweep, const char* cause) {
  std::uniform_real_distribution<double> u(u0, u1), v(v0, v1), d(o.hole_min_mm, o.hole_max_mm);
  ScanHole h;
  h.uv = Eigen::Vector2d(u(*rng), v(*rng));
  h.centre = surface.Position(h.uv.x(), h.uv.y());
  h.diameter_mm = d(*rng);
  h.sweep = sweep;
  h.cause = cause;
  return h;
}

Eigen::Vector2d ClampToDomain(const Eigen::Vector2d& uv) {
  return {std::clamp(uv.x(), kUMin, kUMax), std::clamp(uv.y(), kVMin, kVMax)};
}

// The part [s0, s1] of the segment base + s a (s in [s0, s1]) inside the domain; false if none.
bool ClipToDomain(const Eigen::Vector2d& base, const Eigen::Vector2d& a, double* s0, double* s1) {
  const double lo[2] = {kUMin, kVMin}, hi[2] = {kUMax, kVMax};
  for (int i = 0; i < 2; ++i) {
    if (a(i) == 0.0) {
      if (base(i) < lo[i] || base(i) > hi[i]) return false;
      continue;
    }
    double t0 = (lo[i] - base(i)) / a(i), t1 = (hi[i] - base(i)) / a(i);
    if (t0 > t1) std::swap(t0, t1);
    *s0 = std::max(*s0, t0);
    *s1 = std::min(*s1, t1);
  }
  return *s1 > *s0;
}

// One sweep along `plan`, holes that apply to it.
Sweep SimulateSweep(const ChestSurface& reference, const ScanOptions& o, int index,
                    const internal::SweepPlan& plan, const std::vector<ScanHole>& holes, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  std::normal_distribution<double> normal(0.0, 1.0);
  const bool random = o.sampling == ScanSampling::kRandom;
  Sweep sweep;
  SweepTruth& truth = sweep.truth;
  truth.strip_u0 = plan.u0;
  truth.strip_u1 = plan.u1;
  truth.strip_v0 = plan.v0;
  truth.strip_v1 = plan.v1;
  truth.breathing_mm = o.breathing_mm * (2.0 * uniform(rng) - 1.0);
  const ChestSurface surface = reference.WithBreathing(truth.breathing_mm);
  const Wander left(&rng, 15.0, 80.0), right(&rng, 15.0, 80.0);
  const Wander shake_x(&rng, 40.0, 150.0), shake_y(&rng, 40.0, 150.0), shake_z(&rng, 40.0, 150.0);
  const Wander tilt_a(&rng, 40.0, 150.0), tilt_b(&rng, 40.0, 150.0);
  const double cos_max = std::cos(o.max_incidence_deg * kDegree);
  // The wand starts a little before the path's start and stops a little after its end (ragged ends).
  internal::SweepWalk walk(plan, &rng);

  std::vector<Eigen::Vector3d> points, hits;
  std::vector<double> us, vs, lines, columns;
  std::vector<std::uint8_t> outliers;
  Eigen::Vector3d pivot = Eigen::Vector3d::Zero(), skin = Eigen::Vector3d::Zero(), sight = pivot;
  std::vector<double> phis;
  int line = 0;
  double step = 0.0;
  for (; walk.Running(); ++line, walk.Advance(step)) {
    const Eigen::Vector2d c = walk.Centre(), cc = ClampToDomain(c), g = walk.Along(), a = walk.Across();
    const SurfacePoint centre = surface.Evaluate(cc.x(), cc.y());
    step = o.spacing_mm / std::max((centre.d_du * g.x() + centre.d_dv * g.y()).norm(), 1.0);
    const double k = line;
    // Wand pose: standoff along the normal, with smooth tremor of position and direction.
    Eigen::Vector3d f = -centre.normal;
    const Eigen::Vector3d across = centre.d_du * a.x() + centre.d_dv * a.y();
    Eigen::Vector3d l = (across - across.dot(f) * f).normalized();
    const Eigen::Vector3d w = f.cross(l);
    const Eigen::Vector3d origin =
        centre.position + (centre.d_du * (c.x() - cc.x()) + centre.d_dv * (c.y() - cc.y())) -
        o.standoff_mm * f + o.tremor_mm * (shake_x(k) * l + shake_y(k) * w + 0.5 * shake_z(k) * f);
    const Eigen::Matrix3d tremor = (Eigen::AngleAxisd(o.tremor_deg * kDegree * tilt_a(k), l) *
                                    Eigen::AngleAxisd(o.tremor_deg * kDegree * tilt_b(k), w))
                                       .toRotationMatrix();
    f = tremor * f;
    l = (tremor * l).normalized();
    pivot += origin;
    skin += centre.position;
    sight += centre.normal;
    // The fan: from one border to the other (each wanders by ragged_mm).
    const double mm_per_a = std::max(across.norm(), 1.0);
    Eigen::Vector2d lo = cc - a * walk.Half() - a * (o.ragged_mm * left(k) / mm_per_a);
    Eigen::Vector2d hi = cc + a * walk.Half() + a * (o.ragged_mm * right(k) / mm_per_a);
    if (walk.Straight()) {
      lo = ClampToDomain(lo);
      hi = ClampToDomain(hi);
      if ((hi - lo).dot(a) <= 0.0) continue;
    } else {
      // A spiral's line is cut where it leaves the domain (the wand passes beyond the chest).
      double s0 = -walk.Half() - o.ragged_mm * left(k) / mm_per_a;
      double s1 = walk.Half() + o.ragged_mm * right(k) / mm_per_a;
      if (!ClipToDomain(c, a, &s0, &s1)) continue;
      lo = c + s0 * a;
      hi = c + s1 * a;
    }
    auto angle = [&](const Eigen::Vector2d& uv) {
      const Eigen::Vector3d e = surface.Position(uv.x(), uv.y()) - origin;
      return std::atan2(e.dot(l), e.dot(f));
    };
    const double phi0 = angle(lo), phi1 = angle(hi);
    const int rays = static_cast<int>(std::ceil((phi1 - phi0) * o.standoff_mm / o.spacing_mm)) + 1;
    if (rays < 2) continue;
    // Grid: `rays` evenly spaced; random: a Poisson number of that mean, uniform over the line's fan and
    // over the band of the path it stands for (tilted along the path by up to half a line spacing).
    const double dphi = (phi1 - phi0) / (rays - 1);
    const int count = random ? std::poisson_distribution<int>(rays)(rng) : rays;
    phis.resize(static_cast<std::size_t>(count));
    for (int r = 0; r < count; ++r)
      phis[r] = random ? phi0 + (phi1 - phi0) * uniform(rng) : phi0 + (phi1 - phi0) * r / (rays - 1);
    if (random) std::sort(phis.begin(), phis.end());
    Eigen::Vector2d guess = lo;
    for (int r = 0; r < count; ++r) {
      const double phi = phis[r];
      Eigen::Vector3d d = (std::cos(phi) * f + std::sin(phi) * l).normalized();
      if (random) {
        const double psi = (uniform(rng) - 0.5) * o.spacing_mm / o.standoff_mm;
        d = (std::cos(psi) * d + std::sin(psi) * f.cross(l).normalized()).normalized();
      }
      const std::optional<RayHit> hit = IntersectRay(surface, origin, d, guess);
      if (!hit) continue;
      guess = hit->uv;
      const double cos_incidence = -d.dot(hit->normal);
      if (cos_incidence < cos_max) continue;
      // Fewer returns at grazing incidence, and a frayed fringe at the ends of the laser line.
      double keep = std::pow(cos_incidence, o.incidence_falloff);
      const bool fringe =
          random ? (phi - phi0 < 3.0 * dphi || phi1 - phi <= 3.0 * dphi) : (r < 3 || r >= rays - 3);
      if (fringe) keep *= 0.5;
      if (uniform(rng) >= keep) continue;
      bool in_hole = false;
      for (const ScanHole& h : holes) {
        if ((h.sweep < 0 || h.sweep == index) && (hit->point - h.centre).norm() < 0.5 * h.diameter_mm)
          in_hole = true;
      }
      if (in_hole) continue;
      // Range noise along the ray; an outlier is thrown 5-50 mm along it, either way.
      const bool outlier = uniform(rng) < o.outlier_fraction;
      double along = o.noise_mm * normal(rng);
      if (outlier) along = (uniform(rng) < 0.5 ? -1.0 : 1.0) * (5.0 + 45.0 * uniform(rng));
      points.push_back(hit->point + along * d);
      hits.push_back(hit->point);
      us.push_back(hit->uv.x());
      vs.push_back(hit->uv.y());
      lines.push_back(line);
      columns.push_back(r);
      outliers.push_back(outlier ? 1 : 0);
    }
  }
  truth.lines = line;
  const Eigen::Index n = static_cast<Eigen::Index>(points.size());
  truth.true_points.resize(n, 3);
  for (Eigen::Index i = 0; i < n; ++i) truth.true_points.row(i) = hits[i].transpose();
  // The tracker's error: a rotation about the pivot and a shift; the sweep's points are reported through
  // it, and T_scan_sweep undoes it. The pivot: the wand's mean position, or the sensor's (tracker_lever_mm
  // off the mean skin point along the mean line of sight).
  if (line > 0 && o.tracker_pivot == TrackerPivot::kLever) {
    truth.pivot = skin / line + o.tracker_lever_mm * sight.normalized();
  } else {
    truth.pivot = line > 0 ? Eigen::Vector3d(pivot / line) : Eigen::Vector3d::Zero();
  }
  const internal::TrackerError e = internal::DrawTrackerError(o, truth.pivot, truth.true_points, &rng);
  const Rigid3& error = e.error;
  truth.T_scan_sweep = error.inverse();
  truth.rotation_error_deg = e.angle_deg;
  truth.translation_error_mm = e.shift_mm;
  truth.skin_rms_mm = e.skin_rms_mm;

  sweep.cloud.positions.resize(n, 3);
  truth.u.resize(n);
  truth.v.resize(n);
  Eigen::VectorXd line_column(n), column_column(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    sweep.cloud.positions.row(i) = (error * points[i]).transpose();
    truth.u(i) = us[i];
    truth.v(i) = vs[i];
    line_column(i) = lines[i];
    column_column(i) = columns[i];
  }
  truth.outlier = std::move(outliers);
  if (!random) {
    sweep.cloud.scalars["line"] = line_column;
    sweep.cloud.scalars["column"] = column_column;
  }
  return sweep;
}

constexpr EnumNames<ScanSampling, 2> kSamplingNames{
    {{ScanSampling::kGrid, "grid"}, {ScanSampling::kRandom, "random"}}};
constexpr EnumNames<SweepPattern, 4> kPatternNames{{{SweepPattern::kVertical, "vertical"},
                                                    {SweepPattern::kHorizontal, "horizontal"},
                                                    {SweepPattern::kPatches, "patches"},
                                                    {SweepPattern::kSpiral, "spiral"}}};
constexpr EnumNames<TrackerPivot, 2> kPivotNames{
    {{TrackerPivot::kWand, "wand"}, {TrackerPivot::kLever, "lever"}}};
constexpr EnumNames<TrackerDraw, 2> kDrawNames{
    {{TrackerDraw::kExact, "exact"}, {TrackerDraw::kUniform, "uniform"}}};

template <class Enum, std::size_t N>
Enum Parse(const EnumNames<Enum, N>& names, const std::string& text, const char* what) {
  return ParseEnum(names, text, [&] {
    return "unknown " + std::string(what) + " '" + text + "' (expected " +
           ListEnumNames(names, "", ", ", " or ") + ")";
  });
}

}  // namespace

std::string ToString(ScanSampling sampling) { return EnumToString(kSamplingNames, sampling); }
std::string ToString(SweepPattern pattern) { return EnumToString(kPatternNames, pattern); }
std::string ToString(TrackerPivot pivot) { return EnumToString(kPivotNames, pivot); }
std::string ToString(TrackerDraw draw) { return EnumToString(kDrawNames, draw); }
ScanSampling ParseScanSampling(const std::string& text) { return Parse(kSamplingNames, text, "sampling"); }
SweepPattern ParseSweepPattern(const std::string& text) {
  return Parse(kPatternNames, text, "sweep pattern");
}
TrackerPivot ParseTrackerPivot(const std::string& text) { return Parse(kPivotNames, text, "tracker pivot"); }
TrackerDraw ParseTrackerDraw(const std::string& text) { return Parse(kDrawNames, text, "tracker draw"); }

bool ScanOptions::IsOriginalScanner() const {
  const ScanOptions d;
  return sampling == d.sampling && pattern == d.pattern && tracker_pivot == d.tracker_pivot &&
         tracker_lever_mm == d.tracker_lever_mm && tracker_draw == d.tracker_draw &&
         tracker_skin_mm == d.tracker_skin_mm;
}

bool ScanOptions::IsValid(std::string* why) const {
  auto fail = [&](const std::string& m) {
    if (why) *why = m;
    return false;
  };
  if (sweeps < 1 || sweeps > 12) return fail("sweeps must be within [1, 12]");
  if (!InRange(overlap, 0.0, 0.8)) return fail("overlap must be within [0, 0.8]");
  if (!InRange(spacing_mm, 0.2, 20.0)) return fail("point spacing must be within [0.2, 20] mm");
  if (!InRange(standoff_mm, 50.0, 500.0)) return fail("standoff must be within [50, 500] mm");
  if (!InRange(noise_mm, 0.0, 5.0)) return fail("noise must be within [0, 5] mm");
  if (!InRange(tracker_deg, 0.0, 10.0)) return fail("tracker rotation error must be within [0, 10] degrees");
  if (!InRange(tracker_mm, 0.0, 50.0)) return fail("tracker translation error must be within [0, 50] mm");
  if (!InRange(breathing_mm, 0.0, 10.0)) return fail("breathing must be within [0, 10] mm");
  if (subject_holes < 0 || subject_holes > 20 || sweep_holes < 0 || sweep_holes > 20) {
    return fail("hole counts must be within [0, 20]");
  }
  if (!InRange(hole_min_mm, 0.0, 200.0) || !InRange(hole_max_mm, hole_min_mm, 200.0)) {
    return fail("hole diameters must satisfy 0 <= min <= max <= 200 mm");
  }
  if (!InRange(ragged_mm, 0.0, 50.0)) return fail("ragged border amplitude must be within [0, 50] mm");
  if (!InRange(outlier_fraction, 0.0, 0.1)) return fail("outlier fraction must be within [0, 0.1]");
  if (!InRange(max_incidence_deg, 1.0, 89.0)) return fail("maximum incidence must be within [1, 89] degrees");
  if (!InRange(incidence_falloff, 0.0, 10.0)) return fail("incidence falloff must be within [0, 10]");
  if (!InRange(tremor_mm, 0.0, 30.0) || !InRange(tremor_deg, 0.0, 10.0)) {
    return fail("tremor must be within [0, 30] mm and [0, 10] degrees");
  }
  if (FindEnum(kSamplingNames, ToString(sampling)) != sampling) return fail("unknown sampling");
  if (FindEnum(kPatternNames, ToString(pattern)) != pattern) return fail("unknown sweep pattern");
  if (FindEnum(kPivotNames, ToString(tracker_pivot)) != tracker_pivot) return fail("unknown tracker pivot");
  if (FindEnum(kDrawNames, ToString(tracker_draw)) != tracker_draw) return fail("unknown tracker draw");
  if (!InRange(tracker_lever_mm, 20.0, 1000.0)) return fail("tracker lever must be within [20, 1000] mm");
  if (!InRange(tracker_skin_mm, 0.0, 50.0))
    return fail("tracker displacement at the skin must be within [0, 50] mm");
  if (tracker_skin_mm > 0.0 && tracker_deg == 0.0 && tracker_mm == 0.0) {
    return fail(
        "a tracker displacement at the skin needs a nonzero tracker rotation or translation (their ratio)");
  }
  return true;
}

Scan SimulateScan(const ChestSurface& surface, const ScanOptions& options, std::uint64_t seed) {
  std::string why;
  if (!options.IsValid(&why)) ThrowUsage("scan options: " + why);
  Scan scan;
  // Where each sweep goes (vertical strips of equal width in u by default, neighbours sharing `overlap`).
  const std::vector<internal::SweepPlan> plans = internal::PlanSweeps(options);
  const int n = options.sweeps;
  // Holes: the subject's own (in every sweep), then each sweep's.
  std::mt19937_64 rng(DeriveSeed(seed, SeedStream::kScan, 0));
  for (int h = 0; h < options.subject_holes; ++h) {
    scan.holes.push_back(
        MakeHole(surface, &rng, options, -0.75, 0.75, 0.1, 0.95, -1, h % 2 ? "dark skin" : "hair"));
  }
  for (int j = 0; j < n; ++j) {
    for (int h = 0; h < options.sweep_holes; ++h) {
      const internal::SweepPlan& p = plans[static_cast<std::size_t>(j)];
      scan.holes.push_back(MakeHole(surface, &rng, options, p.u0, p.u1, p.hole_v0, p.hole_v1, j,
                                    h % 2 ? "glare" : "occlusion"));
    }
  }
  scan.sweeps.resize(n);
#pragma omp parallel for schedule(dynamic)
  for (int j = 0; j < n; ++j) {
    scan.sweeps[j] = SimulateSweep(surface, options, j, plans[static_cast<std::size_t>(j)], scan.holes,
                                   DeriveSeed(seed, SeedStream::kSweep, static_cast<std::uint64_t>(j)));
  }
  return scan;
}

}  // namespace pectus::datasets
