#include "shape/surface/adjust_poses_to_tracker.h"

#include <gtest/gtest.h>

#include <random>

namespace pectus {
namespace {

// Two sweeps of the same 30 x 30 mm patch of the plane z = 0 (1 mm grid, the same sites), each point
// with its own noise along z (sd `sigma`), at their true poses (identity). With `both_sides` every site
// gives two correspondences, sweep 1's point on sweep 0's plane and sweep 0's on sweep 1's (every point
// the source of one and the target of the other, as the merge's final rounds pair every point of an
// overlap); otherwise the even sites give the first and the odd ones the second (no point shared).
std::vector<SweepCorrespondence> PlanePatchPairs(std::mt19937_64* rng, double sigma, bool both_sides) {
  std::normal_distribution<double> noise(0.0, sigma);
  std::vector<Eigen::Vector3d> a, b;
  for (int x = -15; x < 15; ++x) {
    for (int y = -15; y < 15; ++y) {
      a.emplace_back(x, y, noise(*rng));
      b.emplace_back(x, y, noise(*rng));
    }
  }
  std::vector<SweepCorrespondence> out;
  const Eigen::Vector3d up = Eigen::Vector3d::UnitZ();
  for (std::uint32_t k = 0; k < a.size(); ++k) {
    if (both_sides || k % 2 == 0) out.push_back({0, 1, b[k], a[k], up, 1.0, k, k});
    if (both_sides || k % 2 == 1) out.push_back({1, 0, a[k], b[k], up, 1.0, k, k});
  }
  return out;
}

struct Scatter {
  double empirical = 0.0;             // variance of the step's relative height over the trials (mm^2)
  double model = 0.0;                 // the same from the step's information, mean over the trials (mm^2)
  double independent_fraction = 0.0;  // the pair's, mean over the trials
};

// Per trial, fresh noise and the tracker adjustment from the truth, stepped to its fixed point (the robust
// estimate; one step from the truth would understate its scatter): how far the two sweeps' relative
// height scatters, and what the last step's information says of it.
Scatter RelativeHeightScatter(bool both_sides, bool count_shared_points) {
  std::vector<SweepSurface> sweeps(2);  // normal_variance 0: exact normals, nothing spurious
  PosePrior prior;
  prior.T_world_sweep.assign(2, Rigid3::Identity());
  prior.centre.assign(2, Eigen::Vector3d::Zero());
  prior.rotation_sd_deg = 5.0;  // a loose tracker: the data decide the height
  prior.translation_sd_mm = 10.0;
  TrackerAdjustmentOptions options;
  options.count_shared_points = count_shared_points;
  std::mt19937_64 rng(13);
  const int trials = 200;
  Eigen::VectorXd e = Eigen::VectorXd::Zero(12);
  e(5) = -1.0;
  e(11) = 1.0;
  Scatter out;
  double sum = 0.0, sum2 = 0.0;
  for (int t = 0; t < trials; ++t) {
    const auto pairs = PlanePatchPairs(&rng, 0.1, both_sides);
    std::vector<Rigid3> P(2, Rigid3::Identity());
    TrackerAdjustmentResult r;
    for (int step = 0; step < 4; ++step) r = AdjustPosesToTracker(pairs, sweeps, prior, &P, options);
    const double dz = P[1].translation().z() - P[0].translation().z();
    sum += dz;
    sum2 += dz * dz;
    out.model += e.dot(r.information.ldlt().solve(e)) / trials;
    out.independent_fraction += r.pairs.at(0).independent_fraction / trials;
  }
  out.empirical = sum2 / trials - (sum / trials) * (sum / trials);
  return out;
}

// Every point of the overlap used from both sides: the two sides hold what one holds (two noisy surfaces
// of 900 points, 0.1 mm noise each: the relative height is known to sqrt(2 * 0.01 / 900) = 0.0047 mm,
// and the Cauchy estimate is about 95 % efficient). Counting each point's noise once, the step's
// information says so (variance ratio about 1: 0.7-1.3 allows 3 sd of 200 trials); counting every
// residual as independent, it claims twice what the data hold.
TEST(TrackerAdjustment, EveryPointUsedFromBothSidesCountsItsNoiseOnce) {
  const Scatter counted = RelativeHeightScatter(true, true);
  EXPECT_NEAR(counted.independent_fraction, 0.5, 0.01);
  EXPECT_NEAR(std::sqrt(counted.empirical), std::sqrt(2.0 * 0.01 / 900.0),
              0.15 * std::sqrt(2.0 * 0.01 / 900.0));
  EXPECT_GT(counted.empirical / counted.model, 0.7);
  EXPECT_LT(counted.empirical / counted.model, 1.3);

  const Scatter independent = RelativeHeightScatter(true, false);
  EXPECT_NEAR(independent.independent_fraction, 1.0, 1e-12);
  EXPECT_NEAR(independent.empirical, counted.empirical, 1e-3 * counted.empirical);  // the same step
  EXPECT_NEAR(counted.model / independent.model, 2.0, 0.05);
}

// No point shared (each site gives one correspondence, the sides alternating): nothing to count, the
// information is the residuals' and matches the scatter.
TEST(TrackerAdjustment, CorrespondencesSharingNoPointKeepTheirInformation) {
  const Scatter counted = RelativeHeightScatter(false, true);
  EXPECT_NEAR(counted.independent_fraction, 1.0, 1e-12);
  EXPECT_GT(counted.empirical / counted.model, 0.7);
  EXPECT_LT(counted.empirical / counted.model, 1.3);
}

}  // namespace
}  // namespace pectus
