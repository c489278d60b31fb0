// The response emulator on synthetic field families with a known answer: a family of rank 3 (times a lift
// that depends on the inputs) is reproduced for new inputs to a stated accuracy with exactly 3 components
// kept; with patient-to-patient noise the predicted 2-sigma band covers most errors; the failure paths.
#include "planner_plugin/surrogate/response_emulator.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "shape/core/error.h"

namespace pectus::planner {
namespace {

// n patients of 3 inputs in [-1, 1]; per position (2), a response of m = 3 x 100 coordinates:
// lift(x) (mean + sum_k a_k(x) phi_k), lift = exp(0.3 x0 - 0.2 x1 + 0.1 p) / 100 mm/N, three smooth scores.
struct Family {
  Eigen::MatrixXd x, lift;
  std::vector<Eigen::MatrixXd> responses;
};

Family MakeFamily(int n, unsigned seed, double noise_sd) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::normal_distribution<double> noise(0.0, noise_sd);
  const int m = 300;
  Eigen::MatrixXd phi(m, 3);
  Eigen::VectorXd mean(m);
  for (int j = 0; j < m; ++j) {
    const double t = j / static_cast<double>(m);
    mean(j) = std::exp(-20.0 * (t - 0.5) * (t - 0.5));
    phi(j, 0) = std::sin(2.0 * M_PI * t);
    phi(j, 1) = std::cos(6.0 * M_PI * t);
    phi(j, 2) = t * t - 0.3;
  }
  Family f;
  f.x.resize(n, 3);
  f.lift.resize(n, 2);
  f.responses.assign(2, Eigen::MatrixXd(n, m));
  for (int i = 0; i < n; ++i) {
    for (int d = 0; d < 3; ++d) f.x(i, d) = u(rng);
    const Eigen::Vector3d x = f.x.row(i).transpose();
    for (int p = 0; p < 2; ++p) {
      const double lift = std::exp(0.3 * x(0) - 0.2 * x(1) + 0.1 * p) / 100.0;
      const Eigen::Vector3d a(0.3 * std::sin(x(0) + x(2)) + 0.1 * p, 0.2 * x(1) * x(1),
                              0.1 * x(2) - 0.05 * x(0));
      Eigen::VectorXd shape = mean + phi * a;
      for (int j = 0; j < m; ++j) shape(j) += noise(rng);
      f.lift(i, p) = lift;
      f.responses[p].row(i) = lift * shape.transpose();
    }
  }
  return f;
}

TEST(ResponseEmulatorTest, ReproducesALowRankFieldFamily) {
  const Family train = MakeFamily(40, 1, 0.0), test = MakeFamily(20, 2, 0.0);
  // The family is the lift times a rank-3 shape: divided by the lift, exactly 3 components.
  ResponseEmulatorOptions options;
  options.scale = ResponseScale::kLift;
  const ResponseEmulator emulator(train.x, train.lift, train.responses, options);
  ASSERT_EQ(emulator.summary().components.size(), 2u);
  EXPECT_EQ(emulator.summary().components[0], 3) << emulator.summary().message;
  EXPECT_EQ(emulator.summary().components[1], 3);
  double worst = 0.0, worst_lift = 0.0, sum = 0.0;
  for (int i = 0; i < 20; ++i) {
    const ResponseEmulatorPrediction p = emulator.Predict(test.x.row(i).transpose());
    for (int k = 0; k < 2; ++k) {
      const Eigen::VectorXd fe = test.responses[k].row(i).transpose();
      worst = std::max(worst, (p.response[k] - fe).norm() / fe.norm());
      sum += (p.response[k] - fe).norm() / fe.norm();
      worst_lift = std::max(worst_lift, std::abs(p.lift_per_newton(k) / test.lift(i, k) - 1.0));
    }
  }
  // Smooth scores of 3 inputs learnt from 40 patients: the relative L2 error within 0.5 % on average and
  // 1.5 % at worst (new inputs near the box's corners); the log-linear lift exactly (the linear mean).
  EXPECT_LT(sum / 40.0, 0.005);
  EXPECT_LT(worst, 0.015);
  EXPECT_LT(worst_lift, 1e-9);
}

TEST(ResponseEmulatorTest, TwoSigmaBandCoversNoisyFamily) {
  // Patient-to-patient noise of 0.02 on the shapes (about 5 % of their spread): the band, from the
  // processes and the leave-one-out residual of the modes, should hold about 95 % of the coordinates.
  const Family train = MakeFamily(40, 3, 0.02), test = MakeFamily(30, 4, 0.02);
  ResponseEmulatorOptions options;
  options.explained_fraction = 0.95;
  const ResponseEmulator emulator(train.x, train.lift, train.responses, options);
  double within = 0.0, count = 0.0;
  for (int i = 0; i < 30; ++i) {
    const ResponseEmulatorPrediction p = emulator.Predict(test.x.row(i).transpose());
    for (int k = 0; k < 2; ++k) {
      const Eigen::ArrayXd e = (p.response[k] - test.responses[k].row(i).transpose()).array();
      within += static_cast<double>((e.abs() <= 2.0 * p.response_sd[k].array()).count());
      count += static_cast<double>(e.size());
    }
  }
  EXPECT_GT(within / count, 0.90);
  EXPECT_LT(within / count, 0.99);
}

TEST(ResponseEmulatorTest, FailuresThrowWithAMessage) {
  const Family f = MakeFamily(8, 5, 0.0);
  auto message = [&](const auto& call) -> std::string {
    try {
      call();
    } catch (const Error& e) {
      return e.what();
    }
    return "no throw";
  };
  ResponseEmulatorOptions bad;
  bad.explained_fraction = 0.0;
  EXPECT_NE(message([&] { ResponseEmulator(f.x, f.lift, f.responses, bad); }).find("explained_fraction"),
            std::string::npos);
  EXPECT_NE(message([&] {
              ResponseEmulator(f.x.topRows(4), f.lift.topRows(4),
                               {f.responses[0].topRows(4), f.responses[1].topRows(4)});
            }).find("4 patients, at least 5 needed"),
            std::string::npos);
  EXPECT_NE(
      message([&] { ResponseEmulator(f.x, f.lift, {f.responses[0]}); }).find("2 positions of lifts but 1"),
      std::string::npos);
  EXPECT_NE(message([&] {
              ResponseEmulator(f.x, f.lift, {f.responses[0], f.responses[1].leftCols(10)});
            }).find("position 1 are 8 by 10, not 8 by 300"),
            std::string::npos);
  Eigen::MatrixXd negative = f.lift;
  negative(2, 1) = -1.0;
  EXPECT_NE(message([&] { ResponseEmulator(f.x, negative, f.responses); }).find("> 0"), std::string::npos);
  const ResponseEmulator emulator(f.x, f.lift, f.responses);
  EXPECT_NE(message([&] { emulator.Predict(Eigen::VectorXd::Zero(4)); }).find("4 parameters"),
            std::string::npos);
}

}  // namespace
}  // namespace pectus::planner
