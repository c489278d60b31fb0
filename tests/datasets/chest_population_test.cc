// Tests of datasets/chest_population: the exact mean and modes, and convergence of a sampled cohort's
// empirical mean and PCA to them.
#include "datasets/chest_population.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>

#include "datasets/seeding.h"

namespace pectus::datasets {
namespace {

const ShapeGrid kGrid{21, 41};

// Shape vectors (one row per subject, x1 y1 z1 x2 ...) of the first n subjects of a cohort.
Eigen::MatrixXd CohortShapes(const PopulationModel& population, int n, std::uint64_t seed) {
  Eigen::MatrixXd X(n, 3 * kGrid.size());
  for (int i = 0; i < n; ++i) {
    const SubjectSample s = SampleSubject(population, DeriveSeed(seed, SeedStream::kSubject, i));
    const Points3 P = SampleGrid(ChestSurface(s.parameters), kGrid);
    X.row(i) = Eigen::Map<const Eigen::RowVectorXd>(P.data(), P.size());
  }
  return X;
}

Eigen::VectorXd Flatten(const Points3& P) { return Eigen::Map<const Eigen::VectorXd>(P.data(), P.size()); }

TEST(ChestPopulation, TrueStatisticsReproduceTheCovarianceOfTheParameters) {
  const PopulationModel population = PopulationModel::Default();
  const TrueShapeStatistics st = ComputeTrueShapeStatistics(population, kGrid, 8);
  ASSERT_EQ(st.modes.size(), 8u);
  for (int j = 0; j < 8; ++j) {
    EXPECT_NEAR(Flatten(st.modes[j]).norm(), 1.0, 1e-9);
    if (j > 0) {
      EXPECT_LE(st.eigenvalues(j), st.eigenvalues(j - 1));
    }
    // The surface of mean + t * mode_parameters(:, j) is the mean moved by t * mode j (the model is affine).
    ChestParameters p = population.mean;
    SetLinearPart(LinearPart(population.mean) + 2.0 * st.mode_parameters.col(j), &p);
    const Points3 moved = SampleGrid(ChestSurface(p), kGrid);
    EXPECT_LT((Flatten(moved) - Flatten(st.mean) - 2.0 * Flatten(st.modes[j])).norm(), 1e-8) << "mode " << j;
    // AlongMode moves by sd * sqrt(eigenvalue) along the unit mode.
    const Points3 along = SampleGrid(ChestSurface(AlongMode(population, st, j, 1.5)), kGrid);
    EXPECT_NEAR((Flatten(along) - Flatten(st.mean)).norm(), 1.5 * std::sqrt(st.eigenvalues(j)), 1e-6);
  }
  EXPECT_GT(st.explained.head(6).sum(), 0.99);  // six latent factors carry nearly all variance
}

// The acceptance test: at N = 200 the empirical mean is within twice its expected standard error of the true
// mean (RMS over coordinates), the first three modes (well separated eigenvalues) are within 0.2 rad of the
// true ones
// (|cos| >= 0.98), their eigenvalues within 30 % (the standard error of an eigenvalue is sqrt(2 / N) = 10 %),
// and the subspace of the first six empirical modes captures at least 99 % of the variance that the true six
// capture. And every error shrinks from N = 25 to N = 200.
TEST(ChestPopulation, EmpiricalMeanAndModesConvergeToTheTruth) {
  const PopulationModel population = PopulationModel::Default();
  const TrueShapeStatistics st = ComputeTrueShapeStatistics(population, kGrid, 6);
  const Eigen::VectorXd true_mean = Flatten(st.mean);
  const Eigen::Index m = true_mean.size();
  Eigen::MatrixXd true_modes(m, 6);
  for (int j = 0; j < 6; ++j) true_modes.col(j) = Flatten(st.modes[j]);
  const Eigen::MatrixXd all = CohortShapes(population, 200, 7);
  struct Errors {
    double mean_rms, mode_angle[3], eigenvalue_ratio[3], captured;
  };
  auto measure = [&](int n) {
    const Eigen::MatrixXd X = all.topRows(n);
    const Eigen::RowVectorXd mean = X.colwise().mean();
    const Eigen::MatrixXd C = X.rowwise() - mean;
    Errors e;
    e.mean_rms = (mean.transpose() - true_mean).norm() / std::sqrt(static_cast<double>(m));
    const Eigen::BDCSVD<Eigen::MatrixXd> svd(C, Eigen::ComputeThinV);
    for (int j = 0; j < 3; ++j) {
      e.mode_angle[j] = std::acos(std::min(1.0, std::abs(svd.matrixV().col(j).dot(true_modes.col(j)))));
      e.eigenvalue_ratio[j] = svd.singularValues()(j) * svd.singularValues()(j) / (n - 1) / st.eigenvalues(j);
    }
    // Variance of the true covariance inside the empirical 6-subspace over that inside the true 6-subspace.
    const Eigen::MatrixXd V = svd.matrixV().leftCols(6);
    const Eigen::MatrixXd P = V.transpose() * true_modes;  // 6 x 6
    double captured = 0.0;
    for (int j = 0; j < 6; ++j) captured += st.eigenvalues(j) * P.col(j).squaredNorm();
    e.captured = captured / st.eigenvalues.sum();
    return e;
  };
  const Errors small = measure(25), large = measure(200);
  const double expected_mean_rms = std::sqrt(st.total_variance / 200.0 / static_cast<double>(m));
  EXPECT_LT(large.mean_rms, 2.0 * expected_mean_rms);
  EXPECT_LT(large.mean_rms, small.mean_rms);
  for (int j = 0; j < 3; ++j) {
    EXPECT_LT(large.mode_angle[j], 0.2) << "mode " << j + 1;
    EXPECT_NEAR(large.eigenvalue_ratio[j], 1.0, 0.3) << "mode " << j + 1;
  }
  EXPECT_LT(large.mode_angle[0] + large.mode_angle[1] + large.mode_angle[2],
            small.mode_angle[0] + small.mode_angle[1] + small.mode_angle[2]);
  EXPECT_GT(large.captured, 0.99);
  EXPECT_GT(large.captured, small.captured);
}

TEST(ChestPopulation, SamplingIsDeterministicPerSeed) {
  const PopulationModel population = PopulationModel::Default();
  const SubjectSample a = SampleSubject(population, 42), b = SampleSubject(population, 42),
                      c = SampleSubject(population, 43);
  EXPECT_EQ(LinearPart(a.parameters), LinearPart(b.parameters));
  EXPECT_NE(LinearPart(a.parameters), LinearPart(c.parameters));
}

}  // namespace
}  // namespace pectus::datasets
