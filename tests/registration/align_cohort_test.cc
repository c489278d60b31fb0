#include "registration/align_cohort.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <random>

#include "registration/pose_error.h"
#include "shape/core/error.h"
#include "synthetic_chest.h"

namespace pectus {
namespace {

// Four chest scans (different samplings, 0.2 mm noise, landmarks with 3 mm noise) at known poses.
std::vector<CohortScan> Cohort(std::vector<Rigid3>* poses) {
  std::vector<CohortScan> scans;
  std::mt19937_64 rng(81);
  for (int i = 0; i < 4; ++i) {
    const Rigid3 T =
        i == 0 ? Rigid3(Rigid3::Identity()) : testing::RandomPose(&rng, 20.0, 100.0);  // scan -> world
    poses->push_back(T);
    CohortScan s;
    s.name = "scan" + std::to_string(i);
    s.cloud = testing::Transformed(testing::SampleChest(15000, 90 + static_cast<std::uint64_t>(i), 0.2),
                                   T.inverse());
    s.landmarks =
        testing::ChestLandmarks(Similarity3::FromRigid(T.inverse()), 3.0, 95 + static_cast<std::uint64_t>(i));
    scans.push_back(std::move(s));
  }
  return scans;
}

// To reference: T_frame_scan_i = T_ref^-1 T_i to 0.05 degrees and 0.1 mm.
TEST(AlignCohort, ToReference) {
  std::vector<Rigid3> poses;
  const std::vector<CohortScan> scans = Cohort(&poses);
  CohortOptions o;
  o.reference = 1;
  const CohortResult r = AlignCohort(scans, o);
  ASSERT_TRUE(r.all_succeeded());
  for (std::size_t i = 0; i < scans.size(); ++i) {
    const Similarity3 expected = Similarity3::FromRigid(poses[1].inverse() * poses[i]);
    const PoseError e =
        ComparePoses(r.T_frame_scan[i], expected, scans[i].cloud.positions.row(0).transpose());
    EXPECT_LT(e.rotation_deg, 0.05) << scans[i].name;
    EXPECT_LT(e.translation_mm, 0.1) << scans[i].name;
  }
}

// Groupwise: all scans land in one frame, the reference's. Relative poses between any two scans to 0.05
// degrees and 0.1 mm; the reference itself gets the identity.
TEST(AlignCohort, GroupwiseWithAndWithoutLandmarks) {
  for (const bool with_landmarks : {true, false}) {
    std::vector<Rigid3> poses;
    std::vector<CohortScan> scans = Cohort(&poses);
    if (!with_landmarks) {
      // Without landmarks the scans start from small disturbances of the truth, placed in the world.
      std::mt19937_64 rng(5);
      for (std::size_t i = 0; i < scans.size(); ++i) {
        scans[i].landmarks.reset();
        const Rigid3 near = testing::RandomPose(&rng, 3.0, 5.0, Eigen::Vector3d(0, 100, 160));
        scans[i].cloud = testing::Transformed(scans[i].cloud, near * poses[i]);
        poses[i] = near.inverse();  // the new scan frame -> world
      }
    }
    CohortOptions o;
    o.mode = CohortMode::kGroupwise;
    const CohortResult r = AlignCohort(scans, o);
    ASSERT_TRUE(r.all_succeeded()) << r.messages[0];
    EXPECT_TRUE(r.converged);
    EXPECT_EQ(with_landmarks, r.procrustes.has_value());
    for (std::size_t i = 1; i < scans.size(); ++i) {
      // T_frame_i^-1 T_frame_0 should equal T_i^-1 T_0 (scan 0 -> scan i).
      const Similarity3 est = r.T_frame_scan[i].Inverse() * r.T_frame_scan[0];
      const Similarity3 truth = Similarity3::FromRigid(poses[i].inverse() * poses[0]);
      const PoseError e = ComparePoses(est, truth, scans[0].cloud.positions.row(0).transpose());
      EXPECT_LT(e.rotation_deg, 0.05) << i;
      EXPECT_LT(e.translation_mm, 0.1) << i;
    }
    const PoseError frame =
        ComparePoses(r.T_frame_scan[0], Similarity3::FromRigid(poses[0].inverse() * poses[0]),
                     Eigen::Vector3d(0, 100, 160));
    EXPECT_LT(frame.translation_mm, 1e-9);
    EXPECT_LT(frame.rotation_deg, 1e-9);
  }
}

TEST(AlignCohort, MixedLandmarksAreAUsageError) {
  std::vector<Rigid3> poses;
  std::vector<CohortScan> scans = Cohort(&poses);
  scans[2].landmarks.reset();
  try {
    AlignCohort(scans);
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::kUsage);
    EXPECT_THAT(e.what(), ::testing::HasSubstr("3 of 4"));
  }
}

}  // namespace
}  // namespace pectus
