#include "datasets/scan_simulator.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>

#include "datasets/seeding.h"
#include "datasets/surface_query.h"
#include "shape/core/error.h"

namespace pectus::datasets {
namespace {

constexpr double kDegree = std::numbers::pi / 180.0;

bool InRange(double x, double lo, double hi) { return std::isfinite(x) && x >= lo && x <= hi; }

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

// One sweep: strip [strip_u0, strip_u1], holes that apply to it.
Sweep SimulateSweep(const ChestSurface& reference, const ScanOptions& o, int index, double strip_u0,
                    double strip_u1, const std::vector<ScanHole>& holes, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  std::normal_distribution<double> normal(0.0, 1.0);
  Sweep sweep;
  SweepTruth& truth = sweep.truth;
  truth.strip_u0 = strip_u0;
  truth.strip_u1 = strip_u1;
  truth.breathing_mm = o.breathing_mm * (2.0 * uniform(rng) - 1.0);
  const ChestSurface surface = reference.WithBreathing(truth.breathing_mm);
  const Wander left(&rng, 15.0, 80.0), right(&rng, 15.0, 80.0);
  const Wander shake_x(&rng, 40.0, 150.0), shake_y(&rng, 40.0, 150.0), shake_z(&rng, 40.0, 150.0);
  const Wander tilt_a(&rng, 40.0, 150.0), tilt_b(&rng, 40.0, 150.0);
  const double uc = 0.5 * (strip_u0 + strip_u1), half = 0.5 * (strip_u1 - strip_u0);
  const double cos_max = std::cos(o.max_incidence_deg * kDegree);
  // The wand starts a little above the top and stops a little below the bottom (ragged ends of the strip).
  double v = kVMax + 0.02 - 0.04 * uniform(rng);
  const double v_end = kVMin - 0.02 + 0.04 * uniform(rng);

  std::vector<Eigen::Vector3d> points, hits;
  std::vector<double> us, vs, lines, columns;
  std::vector<std::uint8_t> outliers;
  Eigen::Vector3d pivot = Eigen::Vector3d::Zero();
  int line = 0;
  double step = 0.0;
  for (; v > v_end; ++line, v -= step) {
    const double v_line = std::clamp(v, kVMin, kVMax);
    const SurfacePoint centre = surface.Evaluate(uc, v_line);
    step = o.spacing_mm / std::max(centre.d_dv.norm(), 1.0);
    const double k = line;
    // Wand pose: standoff along the normal, with smooth tremor of position and direction.
    Eigen::Vector3d f = -centre.normal;
    Eigen::Vector3d l = (centre.d_du - centre.d_du.dot(f) * f).normalized();
    const Eigen::Vector3d w = f.cross(l);
    const Eigen::Vector3d origin = centre.position + (v - v_line) * centre.d_dv - o.standoff_mm * f +
                                   o.tremor_mm * (shake_x(k) * l + shake_y(k) * w + 0.5 * shake_z(k) * f);
    const Eigen::Matrix3d tremor = (Eigen::AngleAxisd(o.tremor_deg * kDegree * tilt_a(k), l) *
                                    Eigen::AngleAxisd(o.tremor_deg * kDegree * tilt_b(k), w))
                                       .toRotationMatrix();
    f = tremor * f;
    l = (tremor * l).normalized();
    pivot += origin;
    // The fan: from the left border to the right one (each wanders by ragged_mm).
    const double mm_per_u = std::max(centre.d_du.norm(), 1.0);
    const double u_left = std::max(kUMin, uc - half - o.ragged_mm * left(k) / mm_per_u);
    const double u_right = std::min(kUMax, uc + half + o.ragged_mm * right(k) / mm_per_u);
    if (u_right <= u_left) continue;
    auto angle = [&](double u) {
      const Eigen::Vector3d e = surface.Position(u, v_line) - origin;
      return std::atan2(e.dot(l), e.dot(f));
    };
    const double phi0 = angle(u_left), phi1 = angle(u_right);
    const int rays = static_cast<int>(std::ceil((phi1 - phi0) * o.standoff_mm / o.spacing_mm)) + 1;
    if (rays < 2) continue;
    Eigen::Vector2d guess(u_left, v_line);
    for (int r = 0; r < rays; ++r) {
      const double phi = phi0 + (phi1 - phi0) * r / (rays - 1);
      const Eigen::Vector3d d = (std::cos(phi) * f + std::sin(phi) * l).normalized();
      const std::optional<RayHit> hit = IntersectRay(surface, origin, d, guess);
      if (!hit) continue;
      guess = hit->uv;
      const double cos_incidence = -d.dot(hit->normal);
      if (cos_incidence < cos_max) continue;
      // Fewer returns at grazing incidence, and a frayed fringe at the ends of the laser line.
      double keep = std::pow(cos_incidence, o.incidence_falloff);
      if (r < 3 || r >= rays - 3) keep *= 0.5;
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
  truth.pivot = line > 0 ? Eigen::Vector3d(pivot / line) : Eigen::Vector3d::Zero();
  // The tracker's error: a rotation about the wand's mean position and a shift; the sweep's points are
  // reported through it, and T_scan_sweep undoes it.
  Rigid3 error = Rigid3::Identity();
  error.linear() = Eigen::AngleAxisd(o.tracker_deg * kDegree, RandomUnit(&rng)).toRotationMatrix();
  error.translation() = truth.pivot - error.linear() * truth.pivot + o.tracker_mm * RandomUnit(&rng);
  truth.T_scan_sweep = error.inverse();
  truth.rotation_error_deg = o.tracker_deg;
  truth.translation_error_mm = o.tracker_mm;

  const Eigen::Index n = static_cast<Eigen::Index>(points.size());
  sweep.cloud.positions.resize(n, 3);
  truth.true_points.resize(n, 3);
  truth.u.resize(n);
  truth.v.resize(n);
  Eigen::VectorXd line_column(n), column_column(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    sweep.cloud.positions.row(i) = (error * points[i]).transpose();
    truth.true_points.row(i) = hits[i].transpose();
    truth.u(i) = us[i];
    truth.v(i) = vs[i];
    line_column(i) = lines[i];
    column_column(i) = columns[i];
  }
  truth.outlier = std::move(outliers);
  sweep.cloud.scalars["line"] = line_column;
  sweep.cloud.scalars["column"] = column_column;
  return sweep;
}

}  // namespace

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
  return true;
}

Scan SimulateScan(const ChestSurface& surface, const ScanOptions& options, std::uint64_t seed) {
  std::string why;
  if (!options.IsValid(&why)) ThrowUsage("scan options: " + why);
  Scan scan;
  // Strips of equal width in u, neighbours sharing `overlap` of it, covering [-1, 1].
  const int n = options.sweeps;
  const double width = (kUMax - kUMin) / (n - (n - 1) * options.overlap);
  std::vector<std::pair<double, double>> strips(n);
  for (int j = 0; j < n; ++j) {
    const double u0 = kUMin + j * width * (1.0 - options.overlap);
    strips[j] = {u0, std::min(kUMax, u0 + width)};
  }
  // Holes: the subject's own (in every sweep), then each sweep's.
  std::mt19937_64 rng(DeriveSeed(seed, SeedStream::kScan, 0));
  for (int h = 0; h < options.subject_holes; ++h) {
    scan.holes.push_back(
        MakeHole(surface, &rng, options, -0.75, 0.75, 0.1, 0.95, -1, h % 2 ? "dark skin" : "hair"));
  }
  for (int j = 0; j < n; ++j) {
    for (int h = 0; h < options.sweep_holes; ++h) {
      scan.holes.push_back(MakeHole(surface, &rng, options, strips[j].first, strips[j].second, 0.05, 0.95, j,
                                    h % 2 ? "glare" : "occlusion"));
    }
  }
  scan.sweeps.resize(n);
#pragma omp parallel for schedule(dynamic)
  for (int j = 0; j < n; ++j) {
    scan.sweeps[j] = SimulateSweep(surface, options, j, strips[j].first, strips[j].second, scan.holes,
                                   DeriveSeed(seed, SeedStream::kSweep, static_cast<std::uint64_t>(j)));
  }
  return scan;
}

}  // namespace pectus::datasets
