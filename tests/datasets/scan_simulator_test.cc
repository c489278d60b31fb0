// Tests of datasets/scan_simulator: every sweep, mapped by its true pose, lies on the true surface within the
// configured noise (outliers excepted); holes, strips, determinism.
#include "datasets/scan_simulator.h"

#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <cmath>

#include "datasets/chest_population.h"
#include "datasets/surface_query.h"
#include "shape/core/error.h"
#include "tests/datasets/sample_chest.h"

namespace pectus::datasets {
namespace {

ScanOptions Options() {
  ScanOptions o;
  o.sweeps = 4;
  o.spacing_mm = 2.0;  // a quarter of the points of the default 1 mm: enough statistics, fast
  o.noise_mm = 0.3;
  o.tracker_deg = 1.0;
  o.tracker_mm = 2.0;
  o.outlier_fraction = 0.01;
  return o;
}

struct Residuals {
  double rms = 0.0, max_abs = 0.0, raw_rms = 0.0, outlier_min = 1e9;  // raw: points without pose to true hits
  std::size_t inliers = 0, outliers = 0;
};

// Signed distances to `surface` of the sweep's points mapped by the true pose; raw_rms without the pose.
Residuals Measure(const ChestSurface& surface, const Sweep& sweep) {
  Residuals r;
  double sum = 0.0, raw = 0.0;
  for (Eigen::Index i = 0; i < sweep.cloud.size(); ++i) {
    const Eigen::Vector3d p = sweep.cloud.positions.row(i).transpose();
    ClosestPointOptions o;
    o.initial_uv = Eigen::Vector2d(sweep.truth.u(i), sweep.truth.v(i));
    const double d = ClosestPoint(surface, sweep.truth.T_scan_sweep * p, o).signed_distance;
    if (sweep.truth.outlier[static_cast<std::size_t>(i)]) {
      ++r.outliers;
      r.outlier_min = std::min(r.outlier_min, std::abs(d));
      continue;
    }
    ++r.inliers;
    sum += d * d;
    r.max_abs = std::max(r.max_abs, std::abs(d));
    raw += (p - sweep.truth.true_points.row(i).transpose()).squaredNorm();
  }
  r.rms = std::sqrt(sum / static_cast<double>(r.inliers));
  r.raw_rms = std::sqrt(raw / static_cast<double>(r.inliers));
  return r;
}

TEST(ScanSimulator, SweepsMappedByTheirTruePoseLieOnTheSurfaceWithinTheNoise) {
  const ChestSurface surface = SampleChest();
  const ScanOptions o = Options();
  const Scan scan = SimulateScan(surface, o, 5);
  ASSERT_EQ(scan.sweeps.size(), 4u);
  std::size_t outliers = 0, total = 0;
  for (const Sweep& sweep : scan.sweeps) {
    ASSERT_GT(sweep.cloud.size(), 2000);
    const Residuals r = Measure(surface, sweep);
    // Noise is along the ray, so its normal part is sigma cos(incidence) <= sigma: RMS within (0.5, 1.05)
    // sigma; no inlier beyond 5.5 sigma (probability < 4e-8 a point).
    EXPECT_LT(r.rms, 1.05 * o.noise_mm);
    EXPECT_GT(r.rms, 0.5 * o.noise_mm);
    EXPECT_LT(r.max_abs, 5.5 * o.noise_mm);
    // Outliers are thrown 5-50 mm along rays at most 75 degrees from the normal: >= 5 cos(75 deg) = 1.29 mm
    // off.
    if (r.outliers) {
      EXPECT_GT(r.outlier_min, 1.2);
    }
    // Without the true pose the tracker's error shows: 2 mm of shift plus 1 degree about the wand's mean
    // position.
    EXPECT_GT(r.raw_rms, 1.5);
    outliers += r.outliers;
    total += r.inliers + r.outliers;
    // The pose is the inverse of an error of exactly the configured size.
    EXPECT_NEAR(Eigen::AngleAxisd(sweep.truth.T_scan_sweep.linear()).angle() * 180.0 / M_PI, 1.0, 1e-9);
  }
  // Outliers: binomial with p = 0.01; 4 standard deviations.
  const double p = o.outlier_fraction, n = static_cast<double>(total);
  EXPECT_NEAR(static_cast<double>(outliers), p * n, 4.0 * std::sqrt(n * p * (1 - p)));
}

TEST(ScanSimulator, NoiseFreePointsAreTheTrueHits) {
  ScanOptions o = Options();
  o.noise_mm = 0.0;
  o.outlier_fraction = 0.0;
  const ChestSurface surface = SampleChest();
  const Scan scan = SimulateScan(surface, o, 9);
  for (const Sweep& sweep : scan.sweeps) {
    for (Eigen::Index i = 0; i < sweep.cloud.size(); i += 7) {
      const Eigen::Vector3d p =
          sweep.truth.T_scan_sweep * Eigen::Vector3d(sweep.cloud.positions.row(i).transpose());
      EXPECT_LT((p - sweep.truth.true_points.row(i).transpose()).norm(), 1e-9);
      EXPECT_LT((surface.Position(sweep.truth.u(i), sweep.truth.v(i)) - p).norm(), 1e-8);
    }
  }
}

TEST(ScanSimulator, BreathingSweepsLieOnTheirBreathingState) {
  ScanOptions o = Options();
  o.breathing_mm = 4.0;
  o.outlier_fraction = 0.0;
  const ChestSurface surface = SampleChest();
  const Scan scan = SimulateScan(surface, o, 21);
  double largest_breath = 0.0;
  for (const Sweep& sweep : scan.sweeps) {
    EXPECT_LE(std::abs(sweep.truth.breathing_mm), 4.0);
    largest_breath = std::max(largest_breath, std::abs(sweep.truth.breathing_mm));
    const Residuals r = Measure(surface.WithBreathing(sweep.truth.breathing_mm), sweep);
    EXPECT_LT(r.rms, 1.05 * o.noise_mm);
  }
  EXPECT_GT(largest_breath, 0.5);
}

TEST(ScanSimulator, HolesStripsAndSpacingAreAsConfigured) {
  const ChestSurface surface = SampleChest();
  ScanOptions o = Options();
  o.subject_holes = 3;
  o.sweep_holes = 1;
  const Scan scan = SimulateScan(surface, o, 4);
  ASSERT_EQ(scan.holes.size(), 3u + 4u);
  for (std::size_t k = 0; k < scan.sweeps.size(); ++k) {
    const SweepTruth& t = scan.sweeps[k].truth;
    for (const ScanHole& h : scan.holes) {
      EXPECT_GE(h.diameter_mm, o.hole_min_mm);
      EXPECT_LE(h.diameter_mm, o.hole_max_mm);
      if (h.sweep >= 0 && h.sweep != static_cast<int>(k)) continue;
      for (Eigen::Index i = 0; i < t.true_points.rows(); ++i) {
        ASSERT_GE((t.true_points.row(i).transpose() - h.centre).norm(), 0.5 * h.diameter_mm);
      }
    }
    // Neighbouring strips overlap: the next strip starts before this one ends (by ~30 % of a strip).
    if (k + 1 < scan.sweeps.size()) {
      const SweepTruth& next = scan.sweeps[k + 1].truth;
      const double width = t.strip_u1 - t.strip_u0;
      EXPECT_NEAR((t.strip_u1 - next.strip_u0) / width, o.overlap, 1e-9);
      EXPECT_LT(next.u.minCoeff(), t.u.maxCoeff());
    }
    // Spacing along a laser line: consecutive columns about spacing_mm apart on the surface (median).
    const Eigen::VectorXd& line = scan.sweeps[k].cloud.scalars.at("line");
    const Eigen::VectorXd& column = scan.sweeps[k].cloud.scalars.at("column");
    std::vector<double> gaps;
    for (Eigen::Index i = 1; i < line.size(); ++i) {
      if (line(i) == line(i - 1) && column(i) == column(i - 1) + 1) {
        gaps.push_back((t.true_points.row(i) - t.true_points.row(i - 1)).norm());
      }
    }
    ASSERT_GT(gaps.size(), 100u);
    std::nth_element(gaps.begin(), gaps.begin() + gaps.size() / 2, gaps.end());
    EXPECT_NEAR(gaps[gaps.size() / 2], o.spacing_mm, 0.3 * o.spacing_mm);
  }
}

TEST(ScanSimulator, DeterministicPerSeed) {
  const ChestSurface surface = SampleChest();
  const ScanOptions o = Options();
  const Scan a = SimulateScan(surface, o, 77), b = SimulateScan(surface, o, 77),
             c = SimulateScan(surface, o, 78);
  for (std::size_t k = 0; k < a.sweeps.size(); ++k) {
    ASSERT_EQ(a.sweeps[k].cloud.positions, b.sweeps[k].cloud.positions);
    EXPECT_TRUE(a.sweeps[k].truth.T_scan_sweep.isApprox(b.sweeps[k].truth.T_scan_sweep, 0.0));
  }
  EXPECT_NE(a.sweeps[0].cloud.size(), c.sweeps[0].cloud.size());
}

// Distances from each true point of `t` inside the strip's middle (away from its borders and ends) to its
// nearest other true point of the same sweep, mm.
std::vector<double> NearestNeighbourDistances(const SweepTruth& t) {
  const double uc = 0.5 * (t.strip_u0 + t.strip_u1), half = 0.5 * (t.strip_u1 - t.strip_u0);
  std::vector<double> d;
  for (Eigen::Index i = 0; i < t.true_points.rows(); ++i) {
    if (std::abs(t.u(i) - uc) > 0.5 * half || t.v(i) < 0.3 || t.v(i) > 0.7) continue;
    double best = 1e9;
    for (Eigen::Index j = 0; j < t.true_points.rows(); ++j) {
      if (j != i) best = std::min(best, (t.true_points.row(i) - t.true_points.row(j)).squaredNorm());
    }
    d.push_back(std::sqrt(best));
  }
  return d;
}

// Random sampling is a Poisson process of the grid's density: the same number of points (within 3 %),
// and nearest-neighbour distances as a Poisson process of intensity 1 / spacing^2 has them (Rayleigh:
// mean 0.5 spacing, coefficient of variation 0.523), not a lattice's (all about one spacing: CV < 0.25).
// Tolerances: mean within 12 % (the surface is curved and the fan's rays spread with incidence), CV within
// [0.42, 0.62].
TEST(ScanSimulator, RandomSamplingIsAPoissonProcessOfTheGridsDensity) {
  const ChestSurface surface = SampleChest();
  ScanOptions o = Options();
  o.sweeps = 3;
  o.noise_mm = 0.0;
  o.outlier_fraction = 0.0;
  o.incidence_falloff = 0.0;
  o.subject_holes = o.sweep_holes = 0;
  auto stats = [](const std::vector<double>& d) {
    double mean = 0.0, var = 0.0;
    for (double x : d) mean += x;
    mean /= static_cast<double>(d.size());
    for (double x : d) var += (x - mean) * (x - mean);
    return std::make_pair(mean, std::sqrt(var / static_cast<double>(d.size())) / mean);
  };
  const Scan grid = SimulateScan(surface, o, 12);
  o.sampling = ScanSampling::kRandom;
  const Scan random = SimulateScan(surface, o, 12);
  for (std::size_t k = 0; k < grid.sweeps.size(); ++k) {
    SCOPED_TRACE("sweep " + std::to_string(k));
    EXPECT_NEAR(static_cast<double>(random.sweeps[k].cloud.size()) / grid.sweeps[k].cloud.size(), 1.0, 0.03);
    EXPECT_EQ(random.sweeps[k].cloud.scalars.count("line"), 0u);
    const auto [grid_mean, grid_cv] = stats(NearestNeighbourDistances(grid.sweeps[k].truth));
    const auto [random_mean, random_cv] = stats(NearestNeighbourDistances(random.sweeps[k].truth));
    EXPECT_LT(grid_cv, 0.25);
    EXPECT_NEAR(grid_mean, o.spacing_mm, 0.25 * o.spacing_mm);
    EXPECT_NEAR(random_mean, 0.5 * o.spacing_mm, 0.12 * 0.5 * o.spacing_mm);
    EXPECT_GT(random_cv, 0.42);
    EXPECT_LT(random_cv, 0.62);
  }
}

// Every pattern, sampling and tracker option: the same seed gives the same sweeps with 1 and 2 threads.
TEST(ScanSimulator, DeterministicPerSeedWhateverTheThreads) {
  const ChestSurface surface = SampleChest();
  ScanOptions o = Options();
  o.sweeps = 3;
  o.spacing_mm = 3.0;
  o.sampling = ScanSampling::kRandom;
  o.tracker_pivot = TrackerPivot::kLever;
  o.tracker_draw = TrackerDraw::kUniform;
  o.tracker_skin_mm = 3.0;
  const int threads = omp_get_max_threads();
  for (SweepPattern pattern :
       {SweepPattern::kVertical, SweepPattern::kHorizontal, SweepPattern::kPatches, SweepPattern::kSpiral}) {
    o.pattern = pattern;
    omp_set_num_threads(1);
    const Scan a = SimulateScan(surface, o, 31);
    omp_set_num_threads(2);
    const Scan b = SimulateScan(surface, o, 31);
    ASSERT_EQ(a.sweeps.size(), b.sweeps.size());
    for (std::size_t k = 0; k < a.sweeps.size(); ++k) {
      ASSERT_GT(a.sweeps[k].cloud.size(), 100) << ToString(pattern);
      ASSERT_EQ(a.sweeps[k].cloud.positions, b.sweeps[k].cloud.positions) << ToString(pattern);
      EXPECT_TRUE(a.sweeps[k].truth.T_scan_sweep.isApprox(b.sweeps[k].truth.T_scan_sweep, 0.0));
    }
  }
  omp_set_num_threads(threads);
}

TEST(ScanSimulator, RejectsInvalidOptions) {
  ScanOptions o;
  o.sweeps = 0;
  EXPECT_THROW(SimulateScan(SampleChest(), o, 1), Error);
  o = ScanOptions();
  o.noise_mm = -1.0;
  EXPECT_THROW(SimulateScan(SampleChest(), o, 1), Error);
  o = ScanOptions();
  o.tracker_lever_mm = 5.0;
  EXPECT_THROW(SimulateScan(SampleChest(), o, 1), Error);
  EXPECT_THROW(ParseSweepPattern("zigzag"), Error);
  EXPECT_EQ(ParseSweepPattern(ToString(SweepPattern::kSpiral)), SweepPattern::kSpiral);
}

}  // namespace
}  // namespace pectus::datasets
