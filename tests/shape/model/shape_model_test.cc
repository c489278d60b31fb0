// PCA of shape vectors: a hand-checked four-subject example, the Gram-matrix route against a direct SVD,
// projection and instances.
#include "shape/model/shape_model.h"

#include <gtest/gtest.h>

#include <Eigen/QR>
#include <Eigen/SVD>
#include <algorithm>
#include <random>

#include "shape/core/error.h"
#include "toy_shapes.h"

namespace pectus {
namespace {

TEST(ShapeModel, HandCheckedFourSubjectExample) {
  const ShapeModel m = BuildShapeModel(testing::ToyShapes());
  EXPECT_TRUE(m.mean.isZero(1e-15));
  ASSERT_EQ(m.num_modes(), 2);
  EXPECT_NEAR(m.variances[0], 6.0, 1e-12);
  EXPECT_NEAR(m.variances[1], 2.0 / 3.0, 1e-12);
  EXPECT_NEAR(m.total_variance, 6.0 + 2.0 / 3.0, 1e-12);
  EXPECT_TRUE(m.basis.col(0).isApprox(Eigen::Vector3d(1, 0, 0), 1e-12));  // sign: largest component > 0
  EXPECT_TRUE(m.basis.col(1).isApprox(Eigen::Vector3d(0, 1, 0), 1e-12));
  EXPECT_NEAR(m.ExplainedFraction()[0], 0.9, 1e-12);
  EXPECT_NEAR(m.CumulativeFraction()[1], 1.0, 1e-12);
  // Scores (Eq. 14's z_n): the coordinates along the modes.
  Eigen::MatrixXd scores(4, 2);
  scores << 3, 0, -3, 0, 0, 1, 0, -1;
  EXPECT_TRUE(m.scores.isApprox(scores, 1e-12));
  // +1 standard deviation of mode 1 is sqrt(6) along x.
  EXPECT_TRUE(m.Instance(Eigen::Vector2d(1, 0)).isApprox(Eigen::Vector3d(std::sqrt(6.0), 0, 0), 1e-12));
}

TEST(ShapeModel, GramRouteEqualsTheSvdOfTheCentredData) {
  std::mt19937 rng(7);
  std::normal_distribution<double> n(0.0, 1.0);
  const int subjects = 12, numbers = 300;
  Eigen::MatrixXd s(subjects, numbers);
  for (int r = 0; r < subjects; ++r) {
    for (int c = 0; c < numbers; ++c) s(r, c) = 100.0 + (c % 7) * n(rng) + 0.1 * n(rng);
  }
  const ShapeModel m = BuildShapeModel(s);
  const Eigen::MatrixXd X = s.rowwise() - s.colwise().mean();
  const Eigen::BDCSVD<Eigen::MatrixXd> svd(X, Eigen::ComputeThinV);
  ASSERT_EQ(m.num_modes(), subjects - 1);
  for (int c = 0; c < m.num_modes(); ++c) {
    EXPECT_NEAR(m.variances[c], svd.singularValues()[c] * svd.singularValues()[c] / (subjects - 1), 1e-9);
    EXPECT_NEAR(std::abs(m.basis.col(c).dot(svd.matrixV().col(c))), 1.0, 1e-9);
  }
  EXPECT_TRUE((m.basis.transpose() * m.basis).isIdentity(1e-10));
  EXPECT_NEAR(m.total_variance, X.squaredNorm() / (subjects - 1), 1e-8);
  // Every training shape is reconstructed exactly with all modes.
  for (int r = 0; r < subjects; ++r) {
    const ShapeProjection p = ProjectShape(m, s.row(r).transpose());
    EXPECT_LT(p.max_error_mm, 1e-9);
    EXPECT_TRUE(p.scores.isApprox(m.scores.row(r).transpose(), 1e-9));
  }
}

// LAPACK's decomposition of a symmetric matrix built from known eigenvalues (1..n, one repeated) and a
// random orthonormal basis: the values ascending, and G v = lambda v, V'V = I to rounding.
TEST(ShapeModel, SymmetricEigenRecoversKnownEigenvalues) {
  const int n = 40;
  std::mt19937 rng(9);
  std::normal_distribution<double> g(0.0, 1.0);
  Eigen::MatrixXd A(n, n);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) A(i, j) = g(rng);
  const Eigen::MatrixXd Q = Eigen::HouseholderQR<Eigen::MatrixXd>(A).householderQ();
  Eigen::VectorXd lambda = Eigen::VectorXd::LinSpaced(n, 1.0, n);
  lambda[1] = lambda[0];  // a repeated eigenvalue
  const Eigen::MatrixXd G = Q * lambda.asDiagonal() * Q.transpose();
  Eigen::VectorXd values;
  Eigen::MatrixXd vectors;
  ASSERT_TRUE(SymmetricEigen(G, &values, &vectors));
  std::sort(lambda.data(), lambda.data() + n);
  EXPECT_LT((values - lambda).cwiseAbs().maxCoeff(), 1e-12 * n);
  EXPECT_LT((G * vectors - vectors * values.asDiagonal()).cwiseAbs().maxCoeff(), 1e-12 * n);
  EXPECT_LT((vectors.transpose() * vectors - Eigen::MatrixXd::Identity(n, n)).cwiseAbs().maxCoeff(), 1e-12);
}

TEST(ShapeModel, ProjectionOfANewShapeReportsTheResidual) {
  const ShapeModel m = BuildShapeModel(testing::ToyShapes());
  // (1, 2, 4): modes give (1, 2); the z = 4 part is outside the model.
  const ShapeProjection p = ProjectShape(m, Eigen::Vector3d(1, 2, 4));
  EXPECT_TRUE(p.scores.isApprox(Eigen::Vector2d(1, 2), 1e-12));
  EXPECT_TRUE(p.scores_sd.isApprox(Eigen::Vector2d(1 / std::sqrt(6.0), 2 / std::sqrt(2.0 / 3.0)), 1e-12));
  EXPECT_NEAR(p.rms_error_mm, 4.0, 1e-12);
  EXPECT_NEAR(p.max_error_mm, 4.0, 1e-12);
  const ShapeProjection one = ProjectShape(m, Eigen::Vector3d(1, 2, 4), 1);
  EXPECT_NEAR(one.rms_error_mm, std::sqrt(4.0 + 16.0), 1e-12);
  EXPECT_THROW(ProjectShape(m, Eigen::Vector3d(1, 2, 4), 3), Error);
  EXPECT_THROW(ProjectShape(m, Eigen::VectorXd::Zero(6)), Error);
}

TEST(ShapeModel, OptionsAndBadInput) {
  ShapeModelOptions o;
  o.max_modes = 1;
  EXPECT_EQ(BuildShapeModel(testing::ToyShapes(), o).num_modes(), 1);
  EXPECT_NEAR(BuildShapeModel(testing::ToyShapes(), o).total_variance, 6.0 + 2.0 / 3.0, 1e-12);
  EXPECT_THROW(BuildShapeModel(Eigen::MatrixXd::Zero(1, 3)), Error);
  EXPECT_THROW(BuildShapeModel(Eigen::MatrixXd::Zero(3, 4)), Error);
  Eigen::MatrixXd nan = testing::ToyShapes();
  nan(1, 1) = std::nan("");
  EXPECT_THROW(BuildShapeModel(nan), Error);
  o.noise_variance = -1.0;
  EXPECT_FALSE(o.IsValid(nullptr));
}

}  // namespace
}  // namespace pectus
