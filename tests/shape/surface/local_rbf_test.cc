#include "shape/surface/local_rbf.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace pectus {
namespace {

// Scattered points in a ball of radius 5 mm about (100, -50, 20) and values of a function there.
LocalRbfProblem Problem(const std::function<double(const Eigen::Vector3d&)>& f, int constraints,
                        int centres) {
  std::mt19937_64 rng(4);
  std::uniform_real_distribution<double> u(-5.0, 5.0);
  LocalRbfProblem p;
  p.origin = Eigen::Vector3d(100.0, -50.0, 20.0);
  p.scale = 5.0;
  p.points.resize(constraints, 3);
  p.values.resize(constraints);
  p.weights = Eigen::VectorXd::Ones(constraints);
  for (int i = 0; i < constraints; ++i) {
    const Eigen::Vector3d x = p.origin + Eigen::Vector3d(u(rng), u(rng), u(rng));
    p.points.row(i) = x.transpose();
    p.values(i) = f(x);
  }
  p.centres = p.points.topRows(centres);
  return p;
}

TEST(LocalRbf, ReproducesAQuadricExactly) {
  // A sphere's implicit |x - c|^2 / (2 r) - r / 2 is a quadric: the degree-2 polynomial part holds it.
  const Eigen::Vector3d c(102.0, -49.0, 19.0);
  auto f = [&](const Eigen::Vector3d& x) { return ((x - c).squaredNorm() - 25.0) / 10.0; };
  const LocalRbfProblem p = Problem(f, 80, 20);
  LocalRbf fit;
  ASSERT_TRUE(fit.Fit(p, 1e-3));
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(-4.0, 4.0);
  for (int i = 0; i < 50; ++i) {
    const Eigen::Vector3d x = p.origin + Eigen::Vector3d(u(rng), u(rng), u(rng));
    EXPECT_NEAR(fit.Evaluate(x), f(x), 1e-7);
  }
}

TEST(LocalRbf, InterpolatesWithoutSmoothingAndSmoothsWithIt) {
  // A function no polynomial of degree 2 holds: the kernels must carry it.
  auto f = [](const Eigen::Vector3d& x) {
    return std::sin(x.x() / 2.0) * std::cos(x.y() / 3.0) + 0.1 * x.z();
  };
  const LocalRbfProblem p = Problem(f, 60, 60);  // one centre per constraint
  LocalRbf exact, smooth;
  ASSERT_TRUE(exact.Fit(p, 0.0));
  ASSERT_TRUE(smooth.Fit(p, 1e-2));
  double worst_exact = 0, worst_smooth = 0;
  for (Eigen::Index i = 0; i < p.points.rows(); ++i) {
    worst_exact = std::max(worst_exact, std::abs(exact.Evaluate(p.points.row(i).transpose()) - p.values(i)));
    worst_smooth =
        std::max(worst_smooth, std::abs(smooth.Evaluate(p.points.row(i).transpose()) - p.values(i)));
  }
  EXPECT_LT(worst_exact, 1e-6) << "Carr et al.'s interpolant (smoothing 0) passes through the data";
  EXPECT_GT(worst_smooth, 1e-3) << "smoothing trades fit for bending energy";
  EXPECT_EQ(exact.num_centres(), 60);
}

TEST(LocalRbf, RefusesConstraintsThatFixNoLinearFunction) {
  auto f = [](const Eigen::Vector3d& x) { return x.x(); };
  LocalRbfProblem p = Problem(f, 30, 10);
  p.points.col(2).setConstant(20.0);  // all constraints in one plane: z is free
  p.centres.col(2).setConstant(20.0);
  LocalRbf fit;
  EXPECT_FALSE(fit.Fit(p, 1e-3));
  LocalRbfProblem few = Problem(f, 3, 3);
  EXPECT_FALSE(fit.Fit(few, 1e-3));
}

}  // namespace
}  // namespace pectus
