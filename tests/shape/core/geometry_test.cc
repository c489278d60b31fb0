#include "shape/core/geometry.h"

#include <gtest/gtest.h>

#include <cmath>

#include "shape/core/error.h"
#include "shape/core/landmarks.h"

namespace pectus {
namespace {

Similarity3 MakeSimilarity(double scale, const Eigen::Vector3d& axis, double angle_rad,
                           const Eigen::Vector3d& t) {
  Similarity3 S;
  S.scale = scale;
  S.rotation = Eigen::AngleAxisd(angle_rad, axis.normalized()).toRotationMatrix();
  S.translation = t;
  return S;
}

TEST(Similarity3, InverseComposesToIdentity) {
  const Similarity3 S = MakeSimilarity(1.7, {1, 2, 3}, 0.8, {10, -20, 30});
  const Eigen::Matrix4d I = S.Matrix() * S.Inverse().Matrix();
  EXPECT_LT((I - Eigen::Matrix4d::Identity()).norm(), 1e-12);
  const Eigen::Vector3d x(4, 5, 6);
  EXPECT_LT((S.Inverse() * (S * x) - x).norm(), 1e-12);
}

TEST(Similarity3, ComposeMatchesTheMatrixProductAndAppliesRightFirst) {
  const Similarity3 A = MakeSimilarity(1.3, {1, 0, 2}, 0.4, {5, 6, -7});
  const Similarity3 B = MakeSimilarity(0.6, {0, 3, 1}, -1.1, {-2, 8, 1});
  const Similarity3 AB = A * B;
  // The same map as the product of the homogeneous matrices; 1e-12 is a few ulps of entries of size 10.
  EXPECT_LT((AB.Matrix() - A.Matrix() * B.Matrix()).norm(), 1e-12);
  const Eigen::Vector3d x(4, -5, 6);
  EXPECT_LT((AB * x - A * (B * x)).norm(), 1e-12);
  EXPECT_NEAR(AB.scale, 1.3 * 0.6, 1e-15);
  EXPECT_TRUE(((AB * B.Inverse()) * B).Matrix().isApprox(AB.Matrix(), 1e-12));
  EXPECT_LT(((A * A.Inverse()).Matrix() - Eigen::Matrix4d::Identity()).norm(), 1e-12);
}

TEST(Similarity3, ApplyMovesEveryRowAsThePointOperator) {
  const Similarity3 S = MakeSimilarity(2.0, {1, 1, 0}, 0.3, {1, 2, 3});
  Points3 x(3, 3);
  x << 1, 0, 0, 0, 1, 0, 3, -4, 5;
  const Points3 y = S.Apply(x);
  for (Eigen::Index i = 0; i < x.rows(); ++i)
    EXPECT_LT((y.row(i).transpose() - S * Eigen::Vector3d(x.row(i).transpose())).norm(), 1e-12);
}

TEST(LandmarkSet, TransformedMovesEveryPositionAndKeepsLabels) {
  LandmarkSet s;
  s.items.push_back({"a", {1, 2, 3}, "first"});
  s.items.push_back({"b", {-4, 0, 9}, ""});
  const Similarity3 T = MakeSimilarity(1.5, {0, 0, 1}, M_PI / 2, {10, 0, 0});
  const LandmarkSet t = s.Transformed(T);
  ASSERT_EQ(t.size(), 2u);
  EXPECT_EQ(t.items[0].label, "a");
  EXPECT_EQ(t.items[0].description, "first");
  // Known answer: a quarter turn about z takes (1, 2, 3) to (-2, 1, 3); times 1.5, plus (10, 0, 0).
  EXPECT_LT((t.items[0].position - Eigen::Vector3d(7, 1.5, 4.5)).norm(), 1e-12);
  EXPECT_LT((t.items[1].position - T * Eigen::Vector3d(-4, 0, 9)).norm(), 1e-12);
}

TEST(Similarity3, FromMatrixRecoversScaleRotationTranslation) {
  const Similarity3 S = MakeSimilarity(0.25, {0, 1, 1}, -2.1, {1e4, 2, -3});
  const Similarity3 R = Similarity3::FromMatrix(S.Matrix(), "T.json");
  EXPECT_NEAR(R.scale, 0.25, 1e-14);
  EXPECT_LT((R.rotation - S.rotation).norm(), 1e-12);
  EXPECT_LT((R.translation - S.translation).norm(), 1e-9);
}

TEST(Similarity3, FromMatrixRejectsShearReflectionAndBadLastRow) {
  Eigen::Matrix4d M = Eigen::Matrix4d::Identity();
  M(0, 1) = 0.3;  // shear
  EXPECT_THROW(Similarity3::FromMatrix(M, "shear.json"), Error);
  M = Eigen::Matrix4d::Identity();
  M(2, 2) = -1;  // reflection
  try {
    Similarity3::FromMatrix(M, "mirror.json");
    FAIL() << "a reflection was accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::kBadInput);
    EXPECT_NE(std::string(e.what()).find("mirror.json"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("reflection"), std::string::npos);
  }
  M = Eigen::Matrix4d::Identity();
  M(3, 0) = 1;
  EXPECT_THROW(Similarity3::FromMatrix(M, "row.json"), Error);
}

TEST(TransformInPlace, MovesPositionsAndRotatesNormals) {
  PointCloud c;
  c.positions.resize(2, 3);
  c.positions << 1, 0, 0, 0, 1, 0;
  c.normals = c.positions;
  const Similarity3 S = MakeSimilarity(2.0, {0, 0, 1}, M_PI / 2, {1, 1, 1});
  TransformInPlace(S, &c);
  EXPECT_LT((c.positions.row(0) - Eigen::RowVector3d(1, 3, 1)).norm(), 1e-12);
  EXPECT_LT((c.positions.row(1) - Eigen::RowVector3d(-1, 1, 1)).norm(), 1e-12);
  EXPECT_LT((c.normals.row(0) - Eigen::RowVector3d(0, 1, 0)).norm(), 1e-12);  // unit, not scaled
}

TEST(PointCloud, AppendKeepsSharedAttributesOnly) {
  PointCloud a, b;
  a.positions = Points3::Random(3, 3);
  a.normals = Points3::Random(3, 3);
  a.scalars["sweep"] = Eigen::VectorXd::Zero(3);
  a.scalars["only_a"] = Eigen::VectorXd::Ones(3);
  b.positions = Points3::Random(2, 3);
  b.scalars["sweep"] = Eigen::VectorXd::Ones(2);
  PointCloud merged;
  merged.Append(a);
  merged.Append(b);
  ASSERT_EQ(merged.size(), 5);
  EXPECT_FALSE(merged.has_normals());  // b has none
  ASSERT_EQ(merged.scalars.count("sweep"), 1u);
  EXPECT_EQ(merged.scalars.count("only_a"), 0u);
  EXPECT_DOUBLE_EQ(merged.scalars["sweep"](4), 1.0);
  EXPECT_EQ(merged.positions.row(3), b.positions.row(0));
}

TEST(PointCloud, ValidateNamesTheFileAndThePoint) {
  PointCloud c;
  c.positions = Points3::Zero(4, 3);
  c.positions(2, 1) = std::nan("");
  try {
    c.Validate("scan.ply");
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.file(), "scan.ply");
    EXPECT_NE(e.message().find("point 2"), std::string::npos);
  }
}

TEST(TriangleMesh, ValidateRejectsOutOfRangeFaces) {
  TriangleMesh m;
  m.vertices.positions = Points3::Zero(3, 3);
  m.faces.resize(1, 3);
  m.faces << 0, 1, 3;
  EXPECT_THROW(m.Validate("m.obj"), Error);
  m.faces << 0, 1, 2;
  EXPECT_NO_THROW(m.Validate("m.obj"));
}

TEST(Bounds3, ExtentAndDiagonal) {
  Points3 p(2, 3);
  p << -1, 0, 2, 3, 3, 2;
  const Bounds3 b = ComputeBounds(p);
  EXPECT_EQ(b.extent(), Eigen::Vector3d(4, 3, 0));
  EXPECT_DOUBLE_EQ(b.diagonal(), 5.0);
  EXPECT_TRUE(ComputeBounds(Points3(0, 3)).empty());
}

}  // namespace
}  // namespace pectus
