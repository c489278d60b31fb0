#include "shape/io/transform_io.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "shape/core/error.h"
#include "shape/io/mapped_file.h"
#include "tests/shape/io/io_test_util.h"

namespace pectus {
namespace {

using testing::ThrowsBadInput;

Similarity3 KnownTransform() {
  Similarity3 T;
  T.scale = 1.7;
  T.rotation = Eigen::AngleAxisd(0.6, Eigen::Vector3d(1, 2, -2).normalized()).toRotationMatrix();
  T.translation = Eigen::Vector3d(12.5, -300.25, 7.0 / 3);
  return T;
}

TEST(TransformIo, JsonFieldsDescribeTheTransform) {
  const nlohmann::json j = TransformToJson(KnownTransform());
  EXPECT_DOUBLE_EQ(j["scale"].get<double>(), 1.7);
  EXPECT_NEAR(j["rotation_deg"].get<double>(), 0.6 * 180 / std::numbers::pi, 1e-10);
  EXPECT_EQ(j["translation_mm"][1].get<double>(), -300.25);
  ASSERT_EQ(j["T_target_source"].size(), 4u);
  EXPECT_EQ(j["T_target_source"][3], nlohmann::json({0.0, 0.0, 0.0, 1.0}));
  EXPECT_EQ(j["T_target_source"][0][3].get<double>(), 12.5);
}

TEST(TransformIo, WriteThenReadRecoversTheTransformAndKeepsExtras) {
  const testing::TempDir dir;
  const Similarity3 T = KnownTransform();
  WriteTransformJson(dir / "t.json", T, {{"rms_mm", 0.42}, {"scale", 99.0}, {"method", "landmarks"}});
  const Similarity3 back = ReadTransformJson(dir / "t.json");
  EXPECT_NEAR(back.scale, T.scale, 1e-12);
  EXPECT_LT((back.rotation - T.rotation).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LT((back.translation - T.translation).cwiseAbs().maxCoeff(), 1e-12);

  const MappedFile file((dir / "t.json").string());
  const nlohmann::json j = nlohmann::json::parse(file.bytes().begin(), file.bytes().end());
  EXPECT_EQ(j["rms_mm"].get<double>(), 0.42);
  EXPECT_EQ(j["method"], "landmarks");
  EXPECT_EQ(j["scale"].get<double>(), 1.7);  // the transform's own fields win
}

TEST(TransformIo, SixteenNumbersRowMajor) {
  const Similarity3 T = ParseTransformJson(
      R"({"T_target_source": [0, -1, 0, 10,  1, 0, 0, 20,  0, 0, 1, 30,  0, 0, 0, 1]})", "flat.json");
  EXPECT_EQ(T.scale, 1.0);
  EXPECT_TRUE((T * Eigen::Vector3d(1, 0, 0)).isApprox(Eigen::Vector3d(10, 21, 30)));
  // A matching scale is accepted.
  const Similarity3 S = ParseTransformJson(
      R"({"T_target_source": [[2, 0, 0, 0], [0, 2, 0, 0], [0, 0, 2, 0], [0, 0, 0, 1]], "scale": 2.0000000001})",
      "scaled.json");
  EXPECT_DOUBLE_EQ(S.scale, 2.0);
  // A rigid transform whose determinant rounds off 1 by an ulp reads back with the stated scale 1 exactly.
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  for (int k = 1; k < 1000 && std::cbrt(R.determinant()) == 1.0; ++k) {
    R = Eigen::AngleAxisd(0.001 * k, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  }
  ASSERT_NE(std::cbrt(R.determinant()), 1.0) << "no rotation found whose determinant rounds off 1";
  nlohmann::json j;
  j["T_target_source"] = {{R(0, 0), R(0, 1), R(0, 2), 5},
                          {R(1, 0), R(1, 1), R(1, 2), 6},
                          {R(2, 0), R(2, 1), R(2, 2), 7},
                          {0, 0, 0, 1}};
  j["scale"] = 1.0;
  EXPECT_EQ(ParseTransformJson(j.dump(), "rigid.json").scale, 1.0);
}

TEST(TransformIo, MalformedInputIsAnErrorNamingTheFile) {
  EXPECT_TRUE(ThrowsBadInput([] { ParseTransformJson("{\"T_target_source\": [1, 2", "cut.json"); },
                             "malformed JSON: parse error at line 1", "cut.json"));
  EXPECT_TRUE(ThrowsBadInput([] { ParseTransformJson("{\"T\": 1}", "key.json"); }, "no \"T_target_source\"",
                             "key.json"));
  EXPECT_TRUE(ThrowsBadInput(
      [] { ParseTransformJson("{\"T_target_source\": [[1,0,0,0],[0,1,0,0],[0,0,1,0]]}", "rows.json"); },
      "4 rows of 4 numbers", "rows.json"));
  EXPECT_TRUE(ThrowsBadInput(
      [] {
        ParseTransformJson("{\"T_target_source\": [[1,0,0,0],[0,1,0,0],[0,0,1,\"a\"],[0,0,0,1]]}",
                           "str.json");
      },
      "row 3, column 4", "str.json"));
  EXPECT_TRUE(ThrowsBadInput(
      [] {
        ParseTransformJson("{\"T_target_source\": [[2,0,0,0],[0,2,0,0],[0,0,2,0],[0,0,0,1]], \"scale\": 1}",
                           "s.json");
      },
      "\"scale\" is 1", "s.json"));
  EXPECT_TRUE(ThrowsBadInput(
      [] {
        ParseTransformJson("{\"T_target_source\": [[1,0.5,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]]}",
                           "shear.json");
      },
      "shear", "shear.json"));
  EXPECT_TRUE(ThrowsBadInput(
      [] {
        ParseTransformJson("{\"T_target_source\": [[-1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]]}",
                           "mirror.json");
      },
      "reflection", "mirror.json"));
  const testing::TempDir dir;
  EXPECT_TRUE(
      ThrowsBadInput([&] { ReadTransformJson(dir.Write("empty.json", "")); }, "file is empty", "empty.json"));
}

}  // namespace
}  // namespace pectus
