// Filling unseen vertices from the other subjects: shapes drawn from a known low-rank model are recovered
// from wrong starting values, seen vertices and fully seen subjects stay as they are, a local bump the
// model cannot predict is joined to the seen rim by the local correction, and bad input is named.
#include "shape/model/impute_missing_vertices.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>

#include "shape/core/error.h"

namespace pectus {
namespace {

using Mask = Eigen::Matrix<bool, Eigen::Dynamic, Eigen::Dynamic>;

// A 21 x 21 grid of vertices, 3 mm apart, in the plane z = 0.
Eigen::MatrixXd GridPositions() {
  Eigen::MatrixXd p(21 * 21, 3);
  for (int i = 0; i < 21; ++i)
    for (int j = 0; j < 21; ++j) p.row(i * 21 + j) << 3.0 * j, 3.0 * i, 0.0;
  return p;
}

// N shapes: the grid displaced along z by three smooth modes with random weights (sd 3, 2, 1 mm), plus
// independent noise of sd `noise` mm on every coordinate. Rows: x1 y1 z1 x2 ...
Eigen::MatrixXd LowRankShapes(int N, double noise, std::mt19937* rng) {
  const Eigen::MatrixXd p = GridPositions();
  std::normal_distribution<double> g(0.0, 1.0);
  Eigen::MatrixXd X(N, 3 * p.rows());
  for (int n = 0; n < N; ++n) {
    const double a = 3.0 * g(*rng), b = 2.0 * g(*rng), c = 1.0 * g(*rng);
    for (Eigen::Index v = 0; v < p.rows(); ++v) {
      const double u = p(v, 0) / 60.0, w = p(v, 1) / 60.0;
      const double z =
          a * std::sin(M_PI * u) * std::sin(M_PI * w) + b * (u - 0.5) + c * (w - 0.5) * (u + 0.2);
      X.row(n).segment<3>(3 * v) = Eigen::RowVector3d(p(v, 0), p(v, 1), z);
      for (int d = 0; d < 3; ++d) X(n, 3 * v + d) += noise * g(*rng);
    }
  }
  return X;
}

// Vertices within `radius` mm of (cx, cy) unseen for subject n.
void Hide(int n, double cx, double cy, double radius, Mask* seen) {
  const Eigen::MatrixXd p = GridPositions();
  for (Eigen::Index v = 0; v < p.rows(); ++v) {
    if (std::hypot(p(v, 0) - cx, p(v, 1) - cy) <= radius) (*seen)(n, v) = false;
  }
}

double LargestError(const Eigen::MatrixXd& filled, const Eigen::MatrixXd& truth, int n, const Mask& seen) {
  double worst = 0.0;
  for (Eigen::Index v = 0; v < seen.cols(); ++v) {
    if (!seen(n, v))
      worst = std::max(worst, (filled.row(n).segment<3>(3 * v) - truth.row(n).segment<3>(3 * v)).norm());
  }
  return worst;
}

TEST(ImputeMissingVertices, RecoversShapesOfALowRankModelFromWrongStartingValues) {
  std::mt19937 rng(3);
  const Eigen::MatrixXd truth = LowRankShapes(12, 0.01, &rng);
  Mask seen = Mask::Constant(12, 441, true);
  Hide(2, 30.0, 30.0, 10.0, &seen);  // a hole in the middle
  Hide(5, 0.0, 60.0, 15.0, &seen);   // one at a corner (the grid's border)
  Hide(9, 45.0, 15.0, 8.0, &seen);
  Eigen::MatrixXd start = truth;
  for (int n : {2, 5, 9})
    for (Eigen::Index v = 0; v < 441; ++v)
      if (!seen(n, v)) start(n, 3 * v + 2) += 10.0;  // the resampler's fill 10 mm off
  ImputationOptions o;
  o.noise_mm = 0.05;
  for (double scale : {0.0, 10.0}) {
    o.local_scale_mm = scale;
    const ImputationResult r = ImputeMissingVertices(start, seen, o);
    EXPECT_TRUE(r.converged) << r.message;
    for (int n : {2, 5, 9}) {
      EXPECT_LT(LargestError(r.shapes, truth, n, seen), 0.1) << "subject " << n << ", scale " << scale;
      EXPECT_GT(r.filled_vertices[n], 0);
      EXPECT_NEAR(r.largest_change_mm[n], 10.0, 0.2);
    }
    // Seen coordinates and fully seen subjects are untouched.
    for (Eigen::Index n = 0; n < 12; ++n) {
      for (Eigen::Index v = 0; v < 441; ++v) {
        if (seen(n, v)) {
          EXPECT_EQ(r.shapes.row(n).segment<3>(3 * v), start.row(n).segment<3>(3 * v));
        }
      }
    }
    EXPECT_EQ(r.filled_vertices[0], 0);
    EXPECT_NE(r.message.find("of 3 of 12 subjects"), std::string::npos) << r.message;
  }
}

// Many holed subjects whose fills lean on each other: 40 subjects of 36 modes, 60 % of them with a hole of
// 10 mm radius, started 5 mm off. Moving every fill at once overshoots here (the sweeps' moves grow); the
// damped sweeps (ImputeMissingVertices halves its step when they do) settle.
// N shapes of 36 smooth modes, sin(pi p u) sin(pi q w) for p, q = 1..6 with sd 6 / (p + q) mm: more modes
// than a small cohort's model of the others can pin.
Eigen::MatrixXd ManyModeShapes(int N, std::mt19937* rng) {
  const Eigen::MatrixXd p = GridPositions();
  std::normal_distribution<double> g(0.0, 1.0);
  Eigen::MatrixXd X(N, 3 * p.rows());
  for (int n = 0; n < N; ++n) {
    Eigen::MatrixXd a(6, 6);
    for (int i = 0; i < 6; ++i)
      for (int j = 0; j < 6; ++j) a(i, j) = 6.0 / (i + j + 2) * g(*rng);
    for (Eigen::Index v = 0; v < p.rows(); ++v) {
      const double u = p(v, 0) / 60.0, w = p(v, 1) / 60.0;
      double z = 0.0;
      for (int i = 0; i < 6; ++i)
        for (int j = 0; j < 6; ++j)
          z += a(i, j) * std::sin(M_PI * (i + 1) * u) * std::sin(M_PI * (j + 1) * w);
      X.row(n).segment<3>(3 * v) = Eigen::RowVector3d(p(v, 0), p(v, 1), z);
    }
  }
  return X;
}

TEST(ImputeMissingVertices, ManyLargeHolesConvergeInsteadOfOvershooting) {
  std::mt19937 rng(5);
  const int N = 40;
  const Eigen::MatrixXd truth = ManyModeShapes(N, &rng);
  Mask seen = Mask::Constant(N, 441, true);
  std::uniform_real_distribution<double> u(0.0, 60.0);
  for (int n = 0; n < N; ++n)
    if (n % 5 < 3) Hide(n, u(rng), u(rng), 10.0, &seen);
  Eigen::MatrixXd start = truth;
  for (int n = 0; n < N; ++n)
    for (Eigen::Index v = 0; v < 441; ++v)
      if (!seen(n, v)) start(n, 3 * v + 2) += 5.0;
  ImputationOptions o;
  o.noise_mm = 0.05;
  o.local_scale_mm = 0.0;
  o.max_iterations = 60;
  const ImputationResult r = ImputeMissingVertices(start, seen, o);
  // 36 modes and 39 others: the fills are poorly pinned (no better than a few mm) and settle slowly (the
  // last sweep's move 0.04 mm with GCC, 0.10 mm with clang), but they settle, and end nearer the truth
  // than they started; sweeps that move every fill fully ran away to 14 m here (a last move of 27 m).
  EXPECT_LT(r.last_change_mm, 0.5) << r.message;
  double worst = 0.0;
  for (int n = 0; n < N; ++n) worst = std::max(worst, LargestError(r.shapes, truth, n, seen));
  EXPECT_LT(worst, 5.0) << r.message;
}

// A cohort larger than the model of the others (max_others): subjects inside and outside its first
// max_others + 1 rows are filled from a model of max_others of them, which spans the same three modes; with
// max_others at least N - 1 the fill is the every-other-subject one, bit for bit.
TEST(ImputeMissingVertices, AModelOfTheFirstOthersFillsALargerCohort) {
  std::mt19937 rng(5);
  const int N = 30;
  const Eigen::MatrixXd truth = LowRankShapes(N, 0.01, &rng);
  Mask seen = Mask::Constant(N, 441, true);
  Hide(3, 30.0, 30.0, 10.0, &seen);  // within the model's rows
  Hide(17, 0.0, 60.0, 15.0, &seen);  // beyond them
  Hide(29, 45.0, 15.0, 8.0, &seen);
  Eigen::MatrixXd start = truth;
  for (int n : {3, 17, 29})
    for (Eigen::Index v = 0; v < 441; ++v)
      if (!seen(n, v)) start(n, 3 * v + 2) += 10.0;
  ImputationOptions o;
  o.noise_mm = 0.05;
  o.max_others = 12;
  const ImputationResult r = ImputeMissingVertices(start, seen, o);
  EXPECT_TRUE(r.converged) << r.message;
  for (int n : {3, 17, 29}) EXPECT_LT(LargestError(r.shapes, truth, n, seen), 0.1) << "subject " << n;
  // Only the core (the first max_others + 1 rows) feeds back into the fills: without the subjects beyond
  // it, the core's fills are the same (to the rounding of a Gram matrix summed in another order).
  const ImputationResult core = ImputeMissingVertices(start.topRows(13), seen.topRows(13), o);
  EXPECT_EQ(core.iterations, r.iterations);
  EXPECT_LT((core.shapes - r.shapes.topRows(13)).cwiseAbs().maxCoeff(), 1e-9);
  o.max_others = N - 1;
  const ImputationResult all = ImputeMissingVertices(start, seen, o);
  o.max_others = 1000;
  EXPECT_TRUE(ImputeMissingVertices(start, seen, o).shapes == all.shapes);
  EXPECT_FALSE(r.shapes == all.shapes);  // 12 others are not all 29
  for (int n : {3, 17, 29}) EXPECT_LT(LargestError(all.shapes, truth, n, seen), 0.1) << "subject " << n;
  o.max_others = 1;
  EXPECT_THROW(ImputeMissingVertices(start, seen, o), Error);
}

TEST(ImputeMissingVertices, TheLocalCorrectionJoinsABumpTheModelCannotPredict) {
  std::mt19937 rng(5);
  Eigen::MatrixXd truth = LowRankShapes(12, 0.01, &rng);
  // Subject 4 alone has a 2 mm bump of 8 mm sd centred on the rim of its hole: outside every mode.
  const Eigen::MatrixXd p = GridPositions();
  for (Eigen::Index v = 0; v < p.rows(); ++v) {
    const double r2 = std::pow(p(v, 0) - 40.0, 2) + std::pow(p(v, 1) - 30.0, 2);
    truth(4, 3 * v + 2) += 2.0 * std::exp(-r2 / (2.0 * 64.0));
  }
  Mask seen = Mask::Constant(12, 441, true);
  Hide(4, 30.0, 30.0, 10.0, &seen);
  ImputationOptions o;
  o.noise_mm = 0.05;
  o.local_scale_mm = 0.0;
  const double alone = LargestError(ImputeMissingVertices(truth, seen, o).shapes, truth, 4, seen);
  o.local_scale_mm = 8.0;
  o.local_sd_mm = 2.0;
  const double joined = LargestError(ImputeMissingVertices(truth, seen, o).shapes, truth, 4, seen);
  EXPECT_GT(alone, 1.0);  // the population's prediction misses the bump
  std::printf("bump on the rim: largest fill error %.3f mm alone, %.3f mm with the local correction\n", alone,
              joined);
  EXPECT_LT(joined, 0.35 * alone) << "without " << alone << " mm, with the local correction " << joined
                                  << " mm";
}

TEST(ImputeMissingVertices, ASubjectSeenTooLittleIsLeftAsItWasAndReported) {
  std::mt19937 rng(1);
  const Eigen::MatrixXd X = LowRankShapes(6, 0.01, &rng);
  Mask seen = Mask::Constant(6, 441, true);
  Hide(1, 30.0, 30.0, 100.0, &seen);  // nothing seen
  const ImputationResult r = ImputeMissingVertices(X, seen);
  ASSERT_EQ(r.too_little_seen.size(), 1u);
  EXPECT_EQ(r.too_little_seen[0], 1);
  EXPECT_EQ(r.shapes, X);
  EXPECT_NE(r.message.find("seen too little"), std::string::npos) << r.message;
}

TEST(ImputeMissingVertices, BadInputIsNamed) {
  std::mt19937 rng(1);
  const Eigen::MatrixXd X = LowRankShapes(4, 0.01, &rng);
  const Mask seen = Mask::Constant(4, 441, true);
  try {
    ImputeMissingVertices(X, Mask::Constant(4, 440, true), {}, "cohort grids");
    FAIL() << "a mask of the wrong size was accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::kBadInput);
    EXPECT_NE(std::string(e.what()).find("cohort grids"), std::string::npos) << e.what();
  }
  EXPECT_THROW(ImputeMissingVertices(X.topRows(2), seen.topRows(2)), Error);
  Eigen::MatrixXd bad = X;
  bad(1, 5) = std::nan("");
  EXPECT_THROW(ImputeMissingVertices(bad, seen), Error);
  ImputationOptions o;
  o.noise_mm = 0.0;
  EXPECT_THROW(ImputeMissingVertices(X, seen, o), Error);
}

}  // namespace
}  // namespace pectus
