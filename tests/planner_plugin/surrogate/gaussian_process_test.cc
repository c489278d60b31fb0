// The Gaussian process against known functions: a smooth function of four inputs recovered to a stated
// accuracy (both kernels), a linear function reproduced exactly by the linear mean, the noise level of noisy
// data recovered and the predicted 2-sigma band covering about 95 % of new observations, and the failure
// paths.
#include "planner_plugin/surrogate/gaussian_process.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "shape/core/error.h"

namespace pectus::planner {
namespace {

// A smooth function of four inputs in [-1.5, 1.5]: standard deviation about 0.8 over that box.
double Smooth(const Eigen::VectorXd& x) {
  return std::sin(x(0)) + 0.5 * x(1) * x(1) - 0.3 * x(2) + 0.4 * std::cos(1.5 * x(3)) * x(0);
}

Eigen::MatrixXd Uniform(int n, int p, double half, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-half, half);
  Eigen::MatrixXd x(n, p);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < p; ++j) x(i, j) = u(rng);
  return x;
}

TEST(GaussianProcessTest, RecoversASmoothFunctionOfFourInputs) {
  const Eigen::MatrixXd x = Uniform(80, 4, 1.5, 1), test = Uniform(200, 4, 1.2, 2);
  Eigen::VectorXd y(x.rows());
  for (Eigen::Index i = 0; i < x.rows(); ++i) y(i) = Smooth(x.row(i).transpose());
  for (GpKernel kernel : {GpKernel::kMatern52, GpKernel::kSquaredExponential}) {
    GaussianProcessOptions options;
    options.kernel = kernel;
    const GaussianProcess gp(x, y, options);
    EXPECT_TRUE(gp.summary().converged) << gp.summary().message;
    double sum2 = 0.0;
    for (Eigen::Index i = 0; i < test.rows(); ++i) {
      const double e = gp.Predict(test.row(i).transpose()) - Smooth(test.row(i).transpose());
      sum2 += e * e;
    }
    // 80 points in 4 dimensions: within 1 % of the function's spread (0.8) inside the sampled box.
    EXPECT_LT(std::sqrt(sum2 / test.rows()), 0.008) << gp.summary().message;
  }
}

TEST(GaussianProcessTest, LinearMeanReproducesALinearFunction) {
  const Eigen::MatrixXd x = Uniform(20, 3, 2.0, 3);
  const Eigen::VectorXd y = (2.0 * x.col(0) - x.col(1)).array() + 3.0;
  const GaussianProcess gp(x, y);
  for (int k = 0; k < 10; ++k) {
    const Eigen::VectorXd p = Eigen::Vector3d(0.5 * k - 2.5, 3.0 - 0.4 * k, 7.0);  // also far outside
    EXPECT_NEAR(gp.Predict(p), 2.0 * p(0) - p(1) + 3.0, 1e-4);
  }
}

TEST(GaussianProcessTest, NoisyDataNoiseLevelAndTwoSigmaCoverage) {
  const Eigen::MatrixXd x = Uniform(120, 3, 1.5, 4), test = Uniform(2000, 3, 1.3, 5);
  std::mt19937 rng(6);
  std::normal_distribution<double> noise(0.0, 0.1);
  auto f = [](const Eigen::VectorXd& v) { return std::sin(1.5 * v(0)) + 0.3 * v(1) * v(2); };
  Eigen::VectorXd y(x.rows());
  for (Eigen::Index i = 0; i < x.rows(); ++i) y(i) = f(x.row(i).transpose()) + noise(rng);
  const GaussianProcess gp(x, y);
  EXPECT_NEAR(gp.summary().noise_sd, 0.1, 0.025) << gp.summary().message;
  double within = 0.0;
  for (Eigen::Index i = 0; i < test.rows(); ++i) {
    double sd = 0.0;
    const double observed = f(test.row(i).transpose()) + noise(rng);
    within += std::abs(gp.Predict(test.row(i).transpose(), nullptr, &sd) - observed) <= 2.0 * sd;
  }
  // A calibrated 2-sigma band holds 95.4 % of new observations; 2000 of them: +-1 % binomial spread.
  EXPECT_NEAR(within / test.rows(), 0.954, 0.03);
}

TEST(GaussianProcessTest, AConstantInputIsLeftOut) {
  Eigen::MatrixXd x = Uniform(30, 2, 1.0, 7);
  x.col(1).setConstant(5.0);
  const Eigen::VectorXd y = x.col(0).array().sin();
  const GaussianProcess gp(x, y);
  EXPECT_TRUE(std::isinf(gp.summary().length_scales(1)));
  EXPECT_NEAR(gp.Predict(Eigen::Vector2d(0.3, 5.0)), std::sin(0.3), 1e-3);
}

TEST(GaussianProcessTest, FailuresThrowWithAMessage) {
  const Eigen::MatrixXd x = Uniform(10, 2, 1.0, 8);
  const Eigen::VectorXd y = x.col(0);
  GaussianProcessOptions bad;
  bad.starts = 0;
  std::string why;
  EXPECT_FALSE(bad.IsValid(&why));
  EXPECT_NE(why.find("starts"), std::string::npos);
  EXPECT_THROW(GaussianProcess(x, y, bad), Error);
  try {
    GaussianProcess(x, Eigen::VectorXd::Zero(9));
    ADD_FAILURE() << "no throw";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("10 input rows but 9 outputs"), std::string::npos) << e.what();
  }
  try {
    GaussianProcess(x.topRows(4), y.head(4));  // a linear mean in 2 inputs needs 5 points
    ADD_FAILURE() << "no throw";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("too few"), std::string::npos) << e.what();
  }
  Eigen::VectorXd nan = y;
  nan(3) = std::nan("");
  EXPECT_THROW(GaussianProcess(x, nan), Error);
  const GaussianProcess gp(x, y);
  EXPECT_THROW(gp.Predict(Eigen::Vector3d::Zero()), Error);
}

}  // namespace
}  // namespace pectus::planner
