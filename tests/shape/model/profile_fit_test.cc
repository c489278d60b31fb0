// Profile curves: exact recovery of polynomials, spline accuracy on a smooth profile, hole interpolation,
// linear continuation beyond the data, too few points.
#include "shape/model/profile_fit.h"

#include <gtest/gtest.h>

#include <cmath>

#include "shape/core/error.h"

namespace pectus {
namespace {

// A chest-like profile (mm): curvature plus a Gaussian dent.
double Chest(double t) { return -t * t / 320.0 - 15.0 * std::exp(-t * t / (2.0 * 25.0 * 25.0)); }

void Sample(double t0, double t1, double step, double (*f)(double), Eigen::VectorXd* t, Eigen::VectorXd* y,
            double hole_lo = 1e9, double hole_hi = -1e9) {
  std::vector<double> ts, ys;
  for (double x = t0; x <= t1 + 1e-9; x += step) {
    if (x > hole_lo && x < hole_hi) continue;
    ts.push_back(x);
    ys.push_back(f(x));
  }
  *t = Eigen::Map<Eigen::VectorXd>(ts.data(), static_cast<Eigen::Index>(ts.size()));
  *y = Eigen::Map<Eigen::VectorXd>(ys.data(), static_cast<Eigen::Index>(ys.size()));
}

TEST(ProfileFit, PolynomialRecoversACubicExactly) {
  auto cubic = [](double t) { return 2.0 - 0.5 * t + 0.01 * t * t - 1e-4 * t * t * t; };
  Eigen::VectorXd t = Eigen::VectorXd::LinSpaced(40, -60.0, 60.0), y(40);
  for (int k = 0; k < 40; ++k) y[k] = cubic(t[k]);
  ProfileFitOptions o;
  o.kind = ProfileFitKind::kPolynomial;
  o.polynomial_degree = 3;
  const ProfileCurve c = FitProfile(t, y, -80.0, 80.0, o);
  ASSERT_TRUE(c.valid());
  for (double x : {-80.0, -33.3, 0.0, 17.0, 80.0}) EXPECT_NEAR(c(x), cubic(x), 1e-9) << x;
  EXPECT_LT(c.rms_residual(), 1e-10);
}

TEST(ProfileFit, SplineFollowsAChestProfileToAHundredthOfAMillimetre) {
  Eigen::VectorXd t, y;
  Sample(-100.0, 100.0, 0.7, Chest, &t, &y);
  const ProfileCurve c = FitProfile(t, y, -80.0, 80.0, ProfileFitOptions{});
  ASSERT_TRUE(c.valid());
  double worst = 0.0;
  for (double x = -80.0; x <= 80.0; x += 0.37) worst = std::max(worst, std::abs(c(x) - Chest(x)));
  EXPECT_LT(worst, 0.02);
}

TEST(ProfileFit, SplineBridgesA30MillimetreHoleToHalfAMillimetre) {
  Eigen::VectorXd t, y;
  Sample(-100.0, 100.0, 0.7, Chest, &t, &y, -15.0, 15.0);  // the dent's centre is missing
  const ProfileCurve c = FitProfile(t, y, -80.0, 80.0, ProfileFitOptions{});
  ASSERT_TRUE(c.valid());
  double worst = 0.0;
  for (double x = -15.0; x <= 15.0; x += 0.5) worst = std::max(worst, std::abs(c(x) - Chest(x)));
  EXPECT_LT(worst, 0.5);
  EXPECT_NEAR(c.DistanceToData(0.0), 15.3, 1e-9);  // nearest samples at -15.3 and 15.5
  EXPECT_NEAR(c.DistanceToData(30.0), 0.0, 0.4);
}

TEST(ProfileFit, SplineContinuesLinearlyBeyondItsInterval) {
  Eigen::VectorXd t = Eigen::VectorXd::LinSpaced(101, 0.0, 50.0), y = 3.0 + 0.2 * t.array();
  const ProfileCurve c = FitProfile(t, y, 0.0, 50.0, ProfileFitOptions{});
  ASSERT_TRUE(c.valid());
  EXPECT_NEAR(c(-20.0), 3.0 - 4.0, 1e-6);
  EXPECT_NEAR(c(70.0), 3.0 + 14.0, 1e-6);
  EXPECT_NEAR(c.DistanceToData(70.0), 20.0, 1e-12);
}

TEST(ProfileFit, TooFewPointsGiveAnInvalidCurve) {
  ProfileFitOptions o;
  o.kind = ProfileFitKind::kPolynomial;
  o.polynomial_degree = 6;
  Eigen::VectorXd t = Eigen::VectorXd::LinSpaced(5, 0.0, 4.0), y = t;
  EXPECT_FALSE(FitProfile(t, y, 0.0, 4.0, o).valid());
  EXPECT_FALSE(FitProfile(Eigen::VectorXd(), Eigen::VectorXd(), 0.0, 4.0, ProfileFitOptions{}).valid());
  o.polynomial_degree = 0;
  EXPECT_FALSE(o.IsValid(nullptr));
  EXPECT_THROW(ParseProfileFitKind("cubic"), Error);
  EXPECT_EQ(ParseProfileFitKind("poly"), ProfileFitKind::kPolynomial);
}

}  // namespace
}  // namespace pectus
