#include "registration/register_pair.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <random>

#include "registration/pose_error.h"
#include "shape/core/error.h"
#include "shape/io/mesh_io.h"
#include "shape/io/stanford_conf.h"
#include "synthetic_chest.h"
#include "tests/support/require_shared_data.h"

namespace pectus {
namespace {

using ::testing::HasSubstr;

// Landmarks (3 mm noise) then ICP recover a rigid pose to 0.05 degrees and 0.1 mm, in both directions.
TEST(RegisterPair, LandmarksThenIcpBothDirections) {
  const PointCloud fixed = testing::SampleChest(30000, 31, 0.2, -1.3, 0.9);
  std::mt19937_64 rng(32);
  const Rigid3 T = testing::RandomPose(&rng, 40.0, 300.0);
  const PointCloud moving =
      testing::Transformed(testing::SampleChest(30000, 33, 0.2, -0.9, 1.3), T.inverse());
  const Similarity3 truth = Similarity3::FromRigid(T);
  const LandmarkSet fixed_lm = testing::ChestLandmarks({}, 3.0, 34);
  const LandmarkSet moving_lm = testing::ChestLandmarks(truth.Inverse(), 3.0, 35);

  const PairRegistrationResult r = RegisterPair(fixed, moving, &fixed_lm, &moving_lm);
  ASSERT_TRUE(r.success) << r.message;
  ASSERT_TRUE(r.landmarks.has_value());
  ASSERT_TRUE(r.icp.has_value());
  const Eigen::Vector3d c = moving.positions.colwise().mean().transpose();
  const PoseError e = ComparePoses(r.T_target_source, truth, c);
  EXPECT_LT(e.rotation_deg, 0.05);
  EXPECT_LT(e.translation_mm, 0.1);
  // The landmark step alone is off by about the landmark noise.
  EXPECT_GT(ComparePoses(r.landmarks->T_target_source, truth, c).translation_mm, 0.1);

  const PairRegistrationResult back = RegisterPair(moving, fixed, &moving_lm, &fixed_lm);
  ASSERT_TRUE(back.success) << back.message;
  const PoseError eb = ComparePoses(back.T_target_source, truth.Inverse(), truth * c);
  EXPECT_LT(eb.rotation_deg, 0.05);
  EXPECT_LT(eb.translation_mm, 0.1);
}

// Acceptance is decided in RegisterPair, each check under its own name. The moving scan's landmarks are
// all placed 6 mm off (one translation), so the landmark fit absorbs the offset exactly (RMS 0) and
// lands 6 mm from the truth; ICP on the surfaces recovers the truth, which leaves the landmarks 6 mm RMS
// from the fixed ones: an increase of 6 mm over the landmark fit. A 3 mm limit rejects the fine step (with
// fall_back_to_landmarks the landmark pose is kept), a 9 mm limit keeps it.
TEST(RegisterPair, LandmarkRmsIncreaseDecidesAndFallsBackToTheLandmarkPose) {
  const PointCloud fixed = testing::SampleChest(30000, 51, 0.1, -1.3, 0.9);
  std::mt19937_64 rng(52);
  const Similarity3 truth = Similarity3::FromRigid(testing::RandomPose(&rng, 20.0, 100.0));
  const PointCloud moving =
      testing::Transformed(testing::SampleChest(30000, 53, 0.1, -0.9, 1.3), truth.Inverse().RigidPart());
  const LandmarkSet fixed_lm = testing::ChestLandmarks({}, 0.0, 0);
  Similarity3 offset;
  offset.translation = Eigen::Vector3d(0.0, 0.0, 6.0);  // along the chest's axis, 6 mm
  const LandmarkSet moving_lm = testing::ChestLandmarks(truth.Inverse(), 0.0, 0).Transformed(offset);
  const Eigen::Vector3d c = moving.positions.colwise().mean().transpose();

  PairRegistrationOptions o;
  o.max_landmark_rms_mm = 0.0;  // off: only the increase is checked
  o.max_landmark_rms_increase_mm = 9.0;
  const PairRegistrationResult kept = RegisterPair(fixed, moving, &fixed_lm, &moving_lm, {}, o);
  ASSERT_TRUE(kept.success) << kept.message;
  EXPECT_TRUE(kept.refined);
  EXPECT_NEAR(kept.landmarks->rms_mm, 0.0, 1e-6);  // the offset is a rigid motion: fitted exactly
  EXPECT_NEAR(kept.landmark_rms_mm, 6.0, 0.1);     // ICP at the truth (to 0.1 mm, as above)
  EXPECT_LT(ComparePoses(kept.T_target_source, truth, c).translation_mm, 0.1);

  o.max_landmark_rms_increase_mm = 3.0;
  const PairRegistrationResult rejected = RegisterPair(fixed, moving, &fixed_lm, &moving_lm, {}, o);
  EXPECT_FALSE(rejected.success);
  EXPECT_THAT(rejected.message, HasSubstr("further from the fixed ones than the landmark fit"));

  o.fall_back_to_landmarks = true;
  const PairRegistrationResult fallback = RegisterPair(fixed, moving, &fixed_lm, &moving_lm, {}, o);
  ASSERT_TRUE(fallback.success) << fallback.message;
  EXPECT_FALSE(fallback.refined);
  EXPECT_THAT(fallback.message, HasSubstr("the landmark pose is used"));
  EXPECT_NEAR(fallback.landmark_rms_mm, 0.0, 1e-6);
  // The landmark pose: 6 mm from the truth at the moving scan's centroid.
  EXPECT_NEAR(ComparePoses(fallback.T_target_source, truth, c).translation_mm, 6.0, 1e-6);
}

// With scale: the moving scan is the chest enlarged 1.06 times. Exact landmarks give the scale (to
// 1e-9); ICP refines the rigid part. Both directions.
TEST(RegisterPair, SimilarityBothDirections) {
  const PointCloud fixed = testing::SampleChest(30000, 41, 0.0);
  std::mt19937_64 rng(42);
  Similarity3 truth = Similarity3::FromRigid(testing::RandomPose(&rng, 30.0, 200.0));
  truth.scale = 1.0 / 1.06;  // moving -> fixed
  PointCloud moving = testing::SampleChest(30000, 43, 0.0);
  TransformInPlace(truth.Inverse(), &moving);
  const LandmarkSet fixed_lm = testing::ChestLandmarks({}, 0.0, 0);
  const LandmarkSet moving_lm = testing::ChestLandmarks(truth.Inverse(), 0.0, 0);
  PairRegistrationOptions o;
  o.landmarks.estimate_scale = true;
  const PairRegistrationResult r = RegisterPair(fixed, moving, &fixed_lm, &moving_lm, {}, o);
  ASSERT_TRUE(r.success) << r.message;
  const Eigen::Vector3d c = moving.positions.colwise().mean().transpose();
  const PoseError e = ComparePoses(r.T_target_source, truth, c);
  EXPECT_NEAR(r.T_target_source.scale, truth.scale, 1e-9);
  EXPECT_LT(e.rotation_deg, 0.05);
  EXPECT_LT(e.translation_mm, 0.1);

  const PairRegistrationResult back = RegisterPair(moving, fixed, &moving_lm, &fixed_lm, {}, o);
  ASSERT_TRUE(back.success) << back.message;
  EXPECT_NEAR(back.T_target_source.scale, 1.06, 1e-9);
  const PoseError eb = ComparePoses(back.T_target_source, truth.Inverse(), truth * c);
  EXPECT_LT(eb.rotation_deg, 0.05);
  EXPECT_LT(eb.translation_mm, 0.1);
}

// Landmarks only, surface patches around landmarks, and argument errors.
TEST(RegisterPair, LandmarksOnlyAndPatches) {
  const PointCloud fixed = testing::SampleChest(20000, 51, 0.2);
  const PointCloud moving = testing::SampleChest(20000, 52, 0.2);
  const LandmarkSet lm = testing::ChestLandmarks({}, 0.0, 0);
  PairRegistrationOptions o;
  o.refine = false;
  const PairRegistrationResult only = RegisterPair(fixed, moving, &lm, &lm, {}, o);
  EXPECT_TRUE(only.success);
  EXPECT_FALSE(only.icp.has_value());
  EXPECT_LT(ComparePoses(only.T_target_source, {}, Eigen::Vector3d(0, 100, 150)).translation_mm, 1e-9);

  o.refine = true;
  o.patch_radius_mm = 50.0;
  const PairRegistrationResult patches = RegisterPair(fixed, moving, &lm, &lm, {}, o);
  ASSERT_TRUE(patches.success) << patches.message;
  EXPECT_LT(patches.icp->levels.back().source_points, moving.size() / 2);
  const PoseError e = ComparePoses(patches.T_target_source, {}, Eigen::Vector3d(0, 100, 150));
  EXPECT_LT(e.rotation_deg, 0.1);
  EXPECT_LT(e.translation_mm, 0.2);

  EXPECT_THROW(RegisterPair(fixed, moving, &lm, nullptr), Error);             // landmarks on one side only
  EXPECT_THROW(RegisterPair(fixed, moving, nullptr, nullptr, {}, o), Error);  // patches need landmarks
}

// Two landmark labels swapped on the moving scan: whatever ICP then finds is reported as a failure.
TEST(RegisterPair, SwappedLandmarksAreAFailure) {
  const PointCloud fixed = testing::SampleChest(20000, 61, 0.2);
  const PointCloud moving = testing::SampleChest(20000, 62, 0.2);
  const LandmarkSet fixed_lm = testing::ChestLandmarks({}, 0.0, 0);
  LandmarkSet moving_lm = fixed_lm;
  std::swap(moving_lm.items[0].label, moving_lm.items[4].label);  // notch <-> umbilicus
  const PairRegistrationResult r = RegisterPair(fixed, moving, &fixed_lm, &moving_lm);
  EXPECT_FALSE(r.success) << r.message;
  EXPECT_FALSE(r.message.empty());
}

// Real data: Stanford bunny sweeps, placed by bun.conf (read in metres, used in mm), disturbed by 5
// degrees and 10 mm, are brought back to within 0.3 mm RMS of the published placement.
class BunnyPairs : public ::testing::TestWithParam<std::pair<const char*, const char*>> {};

TEST_P(BunnyPairs, BackToPublishedPlacement) {
  PECTUS_REQUIRE_SHARED_FILE(testing_support::kBunnyConf);
  const std::filesystem::path dir = testing_support::BunnyDirectory();
  ReadOptions metres;
  metres.input_units = LengthUnit::kMetre;
  const auto [fixed_name, moving_name] = GetParam();
  const PointCloud fixed = ReadPointCloud(dir / fixed_name, metres);
  const PointCloud moving = ReadPointCloud(dir / moving_name, metres);
  std::vector<ScanPose> poses = ReadStanfordConf(dir / "bun.conf");
  ScaleTranslations(1000.0, &poses);
  auto pose = [&](const std::string& file) {
    for (const ScanPose& p : poses) {
      if (p.file == file) return p.T_common_scan;
    }
    ADD_FAILURE() << file << " not in bun.conf";
    return Rigid3(Rigid3::Identity());
  };
  const Rigid3 published = pose(fixed_name).inverse() * pose(moving_name);  // T_fixed_moving
  const Eigen::Vector3d centre = published * Eigen::Vector3d(moving.positions.colwise().mean().transpose());

  const IcpTarget target(fixed.positions, PairRegistrationOptions().normals, fixed_name);
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    std::mt19937_64 rng(seed);
    const Rigid3 start = testing::RandomPose(&rng, 5.0, 10.0, centre) * published;
    const PairRegistrationResult r = RegisterPair(target, moving, nullptr, nullptr,
                                                  Similarity3::FromRigid(start), PairRegistrationOptions());
    ASSERT_TRUE(r.success) << moving_name << " seed " << seed << ": " << r.message;
    const double rms =
        RmsDisplacement(moving.positions, r.T_target_source, Similarity3::FromRigid(published));
    EXPECT_LE(rms, 0.3) << moving_name << " -> " << fixed_name << " seed " << seed;
    EXPECT_GT(
        RmsDisplacement(moving.positions, Similarity3::FromRigid(start), Similarity3::FromRigid(published)),
        5.0);
  }
}

INSTANTIATE_TEST_SUITE_P(Stanford, BunnyPairs,
                         ::testing::Values(std::pair{"bun000.ply", "bun045.ply"},
                                           std::pair{"bun270.ply", "bun315.ply"}),
                         [](const auto& test_info) {  // "bun000_bun045": a stable CTest name
                           const auto stem = [](std::string f) { return f.substr(0, f.find('.')); };
                           return stem(test_info.param.first) + "_" + stem(test_info.param.second);
                         });

}  // namespace
}  // namespace pectus
