#include "shape/surface/adjust_poses.h"

#include <gtest/gtest.h>

#include <random>

#include "shape/core/error.h"
#include "tests/support/poses.h"

namespace pectus {
namespace {

using testing_support::AxisAnglePose;

// Three sweeps of a bumpy surface z = f(x, y) seen in their own frames; correspondences between every
// pair made exactly at the true poses (the true point q of sweep i nearest each sample p of sweep j).
std::vector<SweepCorrespondence> Correspondences(const std::vector<Rigid3>& truth, double outlier_fraction) {
  auto f = [](double x, double y) { return 5.0 * std::sin(x / 9.0) * std::cos(y / 11.0) + 0.01 * x * y; };
  auto normal = [&](double x, double y) {
    const double h = 1e-5;
    return Eigen::Vector3d(-(f(x + h, y) - f(x - h, y)) / (2 * h), -(f(x, y + h) - f(x, y - h)) / (2 * h),
                           1.0)
        .normalized();
  };
  std::mt19937_64 rng(8);
  std::uniform_real_distribution<double> u(-40.0, 40.0), o(0.0, 1.0);
  std::vector<SweepCorrespondence> out;
  for (std::size_t i = 0; i < truth.size(); ++i)
    for (std::size_t j = 0; j < truth.size(); ++j) {
      if (i == j) continue;
      for (int k = 0; k < 400; ++k) {
        const double x = u(rng), y = u(rng);
        const Eigen::Vector3d world(x, y, f(x, y));
        SweepCorrespondence c;
        c.i = i;
        c.j = j;
        c.p = truth[j].inverse() * world;  // the same surface point seen by both sweeps
        // q: a neighbouring surface point of sweep i (0.36 mm away along the surface), with its normal.
        const Eigen::Vector3d qw(x + 0.3, y - 0.2, f(x + 0.3, y - 0.2));
        c.q = truth[i].inverse() * qw;
        c.n = truth[i].linear().transpose() * normal(x + 0.3, y - 0.2);
        if (o(rng) < outlier_fraction) c.p += truth[j].linear().transpose() * Eigen::Vector3d(0, 0, 8.0);
        out.push_back(c);
      }
    }
  return out;
}

TEST(PoseAdjustment, RecoversPosesFromDisturbedStartsWithOutliers) {
  const std::vector<Rigid3> truth = {AxisAnglePose(10, {1, 2, 3}, {5, -3, 200}),
                                     AxisAnglePose(-20, {0, 1, 0.2}, {-40, 10, 180}),
                                     AxisAnglePose(35, {1, 0, 1}, {30, 30, 210})};
  const auto pairs = Correspondences(truth, 0.1);
  std::vector<Rigid3> poses = truth;
  poses[1] = AxisAnglePose(1.5, {0.3, 1, 0}, {0.5, -0.4, 0.3}) * poses[1];
  poses[2] = AxisAnglePose(-1.0, {1, 0, 0.5}, {-0.3, 0.2, 0.6}) * poses[2];
  PoseAdjustmentOptions o;
  o.anchor = 0;
  // Twice, as the merge's rounds do: the second solve takes its robust scale from the residuals at the
  // first one's answer, so the outliers lose their pull.
  AdjustPoses(pairs, &poses, o);
  const PoseAdjustmentResult r = AdjustPoses(pairs, &poses, o);
  EXPECT_TRUE(poses[0].isApprox(truth[0], 1e-12)) << "the anchor is held";
  for (std::size_t s = 1; s < 3; ++s) {
    const Rigid3 d = poses[s] * truth[s].inverse();
    EXPECT_LT(Eigen::AngleAxisd(d.linear()).angle() * 180.0 / M_PI, 0.01) << s;
    EXPECT_LT((d * Eigen::Vector3d(0, 0, 0) - Eigen::Vector3d(0, 0, 0)).norm(), 0.02) << s;
  }
  EXPECT_TRUE(r.converged) << r.message;
  EXPECT_GT(r.robust_scale_mm, 0.0);
}

TEST(PoseAdjustment, NoCorrespondencesChangeNothingAndBadAnchorIsAUsageError) {
  std::vector<Rigid3> poses = {Rigid3::Identity(), AxisAnglePose(5, {0, 0, 1}, {1, 2, 3})};
  const std::vector<Rigid3> before = poses;
  const PoseAdjustmentResult r = AdjustPoses({}, &poses);
  EXPECT_TRUE(poses[1].isApprox(before[1]));
  EXPECT_EQ(r.rms_after_mm, 0.0);
  PoseAdjustmentOptions o;
  o.anchor = 5;
  EXPECT_THROW(AdjustPoses({}, &poses, o), Error);
}

}  // namespace
}  // namespace pectus
