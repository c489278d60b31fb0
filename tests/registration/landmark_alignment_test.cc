#include "registration/landmark_alignment.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <random>

#include "registration/pose_error.h"
#include "shape/core/error.h"
#include "synthetic_chest.h"

namespace pectus {
namespace {

using ::testing::HasSubstr;

// Five chest-like landmarks (mm): sternal notch, xiphoid, left and right nipples, umbilicus.
Points3 ChestLandmarks() {
  Points3 x(5, 3);
  x << 0, 120, 300,   //
      0, 95, 120,     //
      -95, 115, 200,  //
      92, 118, 205,   //
      2, 100, 0;
  return x;
}

Points3 Apply(const Similarity3& T, const Points3& x) {
  Points3 y(x.rows(), 3);
  for (Eigen::Index i = 0; i < x.rows(); ++i)
    y.row(i) = (T * Eigen::Vector3d(x.row(i).transpose())).transpose();
  return y;
}

LandmarkSet ToSet(const Points3& x, const std::vector<std::string>& labels) {
  LandmarkSet s;
  for (Eigen::Index i = 0; i < x.rows(); ++i)
    s.items.push_back({labels[static_cast<std::size_t>(i)], x.row(i).transpose(), ""});
  return s;
}

const std::vector<std::string> kLabels = {"notch", "xiphoid", "nipple_l", "nipple_r", "umbilicus"};

Similarity3 KnownTransform(double scale) {
  std::mt19937_64 rng(7);
  Similarity3 T = Similarity3::FromRigid(testing::RandomPose(&rng, 37.0, 250.0));
  T.scale = scale;
  return T;
}

// Recovers a rigid transform exactly (1e-9 degrees, 1e-9 mm) in both directions.
TEST(UmeyamaAlignment, RecoversRigidTransformBothDirections) {
  const Points3 x = ChestLandmarks();
  const Similarity3 T = KnownTransform(1.0);
  const Points3 y = Apply(T, x);
  const Eigen::Vector3d c = x.colwise().mean().transpose();
  const PoseError forward = ComparePoses(UmeyamaAlignment(x, y, {}, false), T, c);
  EXPECT_LT(forward.rotation_deg, 1e-9);
  EXPECT_LT(forward.translation_mm, 1e-9);
  const PoseError backward = ComparePoses(UmeyamaAlignment(y, x, {}, false), T.Inverse(), T * c);
  EXPECT_LT(backward.rotation_deg, 1e-9);
  EXPECT_LT(backward.translation_mm, 1e-9);
}

// Recovers a similarity (scale 1.27 and its inverse) to 1e-12 relative scale.
TEST(UmeyamaAlignment, RecoversSimilarityBothDirections) {
  const Points3 x = ChestLandmarks();
  const Similarity3 T = KnownTransform(1.27);
  const Points3 y = Apply(T, x);
  const Eigen::Vector3d c = x.colwise().mean().transpose();
  const Similarity3 forward = UmeyamaAlignment(x, y, {}, true);
  EXPECT_NEAR(forward.scale, 1.27, 1e-12);
  EXPECT_LT(ComparePoses(forward, T, c).translation_mm, 1e-9);
  const Similarity3 backward = UmeyamaAlignment(y, x, {}, true);
  EXPECT_NEAR(backward.scale, 1.0 / 1.27, 1e-12);
  EXPECT_LT(ComparePoses(backward, T.Inverse(), T * c).rotation_deg, 1e-9);
  // Rigid estimation of scaled data keeps s = 1.
  EXPECT_EQ(UmeyamaAlignment(x, y, {}, false).scale, 1.0);
}

// A 10 km offset of both point sets loses no precision (1e-6 mm).
TEST(UmeyamaAlignment, FarFromOrigin) {
  Points3 x = ChestLandmarks();
  x.rowwise() += Eigen::RowVector3d(1e7, -1e7, 3e6);
  const Similarity3 T = KnownTransform(1.0);
  const Points3 y = Apply(T, x);
  const Similarity3 est = UmeyamaAlignment(x, y, {}, false);
  const PoseError e = ComparePoses(est, T, x.row(0).transpose());
  EXPECT_LT(e.rotation_deg, 1e-7);
  EXPECT_LT(e.translation_mm, 1e-6);
}

// A landmark moved by 50 mm but given weight 0 has no influence; with weight 1 it has.
TEST(UmeyamaAlignment, WeightsControlInfluence) {
  Points3 x(6, 3);
  x.topRows(5) = ChestLandmarks();
  x.row(5) << 50, 80, 60;
  const Similarity3 T = KnownTransform(1.0);
  Points3 y = Apply(T, x);
  y.row(5) += Eigen::RowVector3d(50, 0, 0);
  Eigen::VectorXd w = Eigen::VectorXd::Ones(6);
  w(5) = 0.0;
  const Eigen::Vector3d c = x.colwise().mean().transpose();
  EXPECT_LT(ComparePoses(UmeyamaAlignment(x, y, w, false), T, c).translation_mm, 1e-9);
  EXPECT_GT(ComparePoses(UmeyamaAlignment(x, y, {}, false), T, c).translation_mm, 1.0);
}

// A mirrored target still yields a proper rotation (det +1, Umeyama Eq. 39).
TEST(UmeyamaAlignment, NeverReturnsAReflection) {
  const Points3 x = ChestLandmarks();
  Points3 y = x;
  y.col(0) *= -1.0;
  const Similarity3 est = UmeyamaAlignment(x, y, {}, false);
  EXPECT_NEAR(est.rotation.determinant(), 1.0, 1e-12);
}

TEST(AlignLandmarks, MatchesLabelsInAnyOrderAndListsUnmatched) {
  const Points3 x = ChestLandmarks();
  const Similarity3 T = KnownTransform(1.0);
  const LandmarkSet source = ToSet(x, kLabels);
  LandmarkSet target = ToSet(Apply(T, x), kLabels);
  std::reverse(target.items.begin(), target.items.end());
  target.items.push_back({"clavicle_l", Eigen::Vector3d(1, 2, 3), ""});
  const LandmarkAlignmentResult r = AlignLandmarks(source, target);
  EXPECT_LT(ComparePoses(r.T_target_source, T, x.row(0).transpose()).translation_mm, 1e-9);
  EXPECT_EQ(r.labels.size(), 5u);
  EXPECT_THAT(r.unmatched, ::testing::ElementsAre("clavicle_l"));
  EXPECT_LT(r.rms_mm, 1e-9);
  EXPECT_THAT(r.message, HasSubstr("clavicle_l"));

  LandmarkAlignmentOptions strict;
  strict.require_all_labels = true;
  try {
    AlignLandmarks(source, target, strict, "a.mrk.json", "b.mrk.json");
    FAIL() << "unmatched labels accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::kBadInput);
    EXPECT_THAT(e.what(), HasSubstr("clavicle_l"));
    EXPECT_THAT(e.what(), HasSubstr("a.mrk.json"));
  }
}

// A landmark placed 10 mm off shows as the largest residual, named in the message.
TEST(AlignLandmarks, ReportsResiduals) {
  const Points3 x = ChestLandmarks();
  const Similarity3 T = KnownTransform(1.0);
  Points3 y = Apply(T, x);
  y(2, 0) += 10.0;
  const LandmarkAlignmentResult r = AlignLandmarks(ToSet(x, kLabels), ToSet(y, kLabels));
  ASSERT_EQ(r.residuals_mm.size(), 5);
  // The moved landmark has the largest residual, and the message names it.
  Eigen::Index worst = 0;
  r.residuals_mm.maxCoeff(&worst);
  EXPECT_EQ(worst, 2);
  EXPECT_THAT(r.message, HasSubstr("nipple_l"));
  EXPECT_GT(r.rms_mm, 2.0);
  EXPECT_LT(r.rms_mm, 10.0);
}

void ExpectBadInput(const LandmarkSet& a, const LandmarkSet& b, const std::string& fragment) {
  try {
    AlignLandmarks(a, b, {}, "moving.mrk.json", "fixed.mrk.json");
    FAIL() << "accepted: expected an error containing '" << fragment << "'";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::kBadInput) << e.what();
    EXPECT_THAT(e.what(), HasSubstr(fragment));
  }
}

TEST(AlignLandmarks, FewerThanThreeIsAClearError) {
  const Points3 x = ChestLandmarks();
  ExpectBadInput(ToSet(x.topRows(2), kLabels), ToSet(x.topRows(2), kLabels), "at least 3");
}

TEST(AlignLandmarks, CollinearIsAClearError) {
  Points3 x(4, 3);
  x << 0, 0, 0, 10, 10, 10, 20, 20, 20, 35, 35, 35.3;
  ExpectBadInput(ToSet(x, kLabels), ToSet(x, kLabels), "collinear");
}

TEST(AlignLandmarks, MismatchedLabelsAreAClearError) {
  const Points3 x = ChestLandmarks();
  const LandmarkSet a = ToSet(x, kLabels);
  const LandmarkSet b = ToSet(x, {"A", "B", "C", "nipple_r", "umbilicus"});
  ExpectBadInput(a, b, "at least 3 landmarks with the same label");
  ExpectBadInput(a, b, "'notch'");  // names what was found in one set only
}

TEST(AlignLandmarks, DuplicateLabelIsAClearError) {
  const Points3 x = ChestLandmarks();
  ExpectBadInput(ToSet(x, {"a", "b", "c", "d", "a"}), ToSet(x, kLabels), "moving.mrk.json");
}

TEST(AlignLandmarks, InvalidOptionsAreAUsageError) {
  LandmarkAlignmentOptions o;
  o.weights["notch"] = -1.0;
  std::string why;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_THAT(why, HasSubstr("notch"));
  const LandmarkSet s = ToSet(ChestLandmarks(), kLabels);
  try {
    AlignLandmarks(s, s, o);
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::kUsage);
  }
}

}  // namespace
}  // namespace pectus
