// `pectus register` as a user meets it: a pair with landmarks recovers a known pose (10 km from the origin),
// a cohort writes every transform and a summary, a poor fit or unusable landmarks exit non-zero and write
// nothing.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <random>
#include <string>

#include "registration/pose_error.h"
#include "shape/io/landmark_io.h"
#include "shape/io/mesh_io.h"
#include "shape/io/transform_io.h"
#include "tests/registration/synthetic_chest.h"
#include "tests/support/command_test.h"

namespace pectus {
namespace {
namespace fs = std::filesystem;

// Landmarks on the analytic chest, moved by T, with Gaussian noise per axis.
LandmarkSet ChestLandmarks(const Rigid3& T, double noise_mm, std::uint64_t seed) {
  return testing::ChestLandmarks(Similarity3::FromRigid(T), noise_mm, seed);
}

class RegisterCommand : public testing_support::CommandTest {
 protected:
  // One sampling of the chest (0.2 mm noise) in the frame `T_world_scan`^-1, written with its landmarks
  // (3 mm noise) as NAME.ply and NAME.mrk.json.
  void WriteScan(const std::string& name, const Rigid3& T_world_scan, std::uint64_t seed,
                 const fs::path& folder, int points = 20000) const {
    PointCloud c = testing::SampleChest(points, seed, 0.2);
    c.normals.resize(0, 3);
    TransformInPlace(Similarity3::FromRigid(T_world_scan.inverse()), &c);
    WritePointCloud(folder / (name + ".ply"), c);
    WriteLandmarks(folder / (name + ".mrk.json"), ChestLandmarks(T_world_scan.inverse(), 3.0, seed + 7));
  }
  // `pectus register` of the scans written as "moving" and "fixed" with their landmarks, the report to
  // r.json and the transform to T.json, with `extra` options.
  CliRun RegisterMovingToFixed(const std::string& extra) const {
    return Pectus("register " + P("moving.ply") + " --to " + P("fixed.ply") + " --moving-landmarks " +
                  P("moving.mrk.json") + " --fixed-landmarks " + P("fixed.mrk.json") + " --report " +
                  P("r.json") + " --transform " + P("T.json") + " --quiet" + extra);
  }
  nlohmann::json Report() const {
    nlohmann::json report;
    std::ifstream(P("r.json")) >> report;
    return report;
  }
};

// Moving and fixed scans 10 km from the origin, 20 degrees and 100 mm apart: landmarks then ICP give
// T_target_source to 0.05 degrees and 0.1 mm; the moved scan, the transform and the report are written.
TEST_F(RegisterCommand, PairWithLandmarksRecoversTheKnownPoseFarFromTheOrigin) {
  Rigid3 far = Rigid3::Identity();
  far.translation() << 1e7, -1e7, 2e6;
  std::mt19937_64 rng(3);
  const Rigid3 T_true =
      far * testing::RandomPose(&rng, 20.0, 100.0, Eigen::Vector3d(0, 100, 160));  // fixed <- moving
  WriteScan("fixed", far.inverse(), 1, dir_);
  // x_fixed = far x_world and x_fixed = T_true x_moving: the moving scan's T_world_scan is far^-1 T_true.
  WriteScan("moving", far.inverse() * T_true, 2, dir_);
  const CliRun r =
      Pectus("register " + P("moving.ply") + " --to " + P("fixed.ply") + " --moving-landmarks " +
             P("moving.mrk.json") + " --fixed-landmarks " + P("fixed.mrk.json") + " -o " + P("moved.ply") +
             " --transform " + P("T.json") + " --report " + P("r.json") + " --quiet");
  ASSERT_EQ(r.code, 0) << r.output;
  const Similarity3 T = ReadTransformJson(P("T.json"));
  const PointCloud moving = ReadPointCloud(P("moving.ply"));
  const PoseError e =
      ComparePoses(T, Similarity3::FromRigid(T_true), moving.positions.colwise().mean().transpose());
  EXPECT_LT(e.rotation_deg, 0.05);
  EXPECT_LT(e.translation_mm, 0.1);
  EXPECT_EQ(T.scale, 1.0);
  // The moved scan lies on the fixed one: its centroid where the truth puts it (doubles in the PLY).
  const PointCloud moved = ReadPointCloud(P("moved.ply"));
  EXPECT_LT(
      (moved.positions.colwise().mean().transpose() - T_true * moving.positions.colwise().mean().transpose())
          .norm(),
      0.1);
  nlohmann::json report;
  std::ifstream(P("r.json")) >> report;
  EXPECT_TRUE(report["success"].get<bool>());
  EXPECT_LT(report["icp"]["rms_mm"].get<double>(), 0.5);
  EXPECT_EQ(report["landmarks"]["labels"].size(), 5u);
}

// A poor fit (a start 800 mm off, no overlap) exits 1 with the reason and writes nothing, not even the
// report; landmarks with fewer than three labels in common exit 3 naming the file.
TEST_F(RegisterCommand, PoorFitAndUnusableLandmarksExitNonZeroAndWriteNothing) {
  WriteScan("fixed", Rigid3::Identity(), 1, dir_);
  WriteScan("moving", Rigid3::Identity(), 2, dir_);
  Rigid3 away = Rigid3::Identity();
  away.translation() << 800.0, 0.0, 0.0;
  WriteTransformJson(P("start.json"), Similarity3::FromRigid(away));
  const std::size_t before = CountFiles();
  const CliRun poor = Pectus("register " + P("moving.ply") + " --to " + P("fixed.ply") + " --initial " +
                             P("start.json") + " --transform " + P("T.json") + " --report " + P("r.json"));
  EXPECT_EQ(poor.code, 1) << poor.output;
  EXPECT_NE(poor.output.find("overlap"), std::string::npos) << poor.output;
  EXPECT_EQ(CountFiles(), before);

  LandmarkSet two = ChestLandmarks(Rigid3::Identity(), 0.0, 1);
  two.items.resize(2);
  WriteLandmarks(P("two.mrk.json"), two);
  const CliRun bad =
      Pectus("register " + P("moving.ply") + " --to " + P("fixed.ply") + " --moving-landmarks " +
             P("two.mrk.json") + " --fixed-landmarks " + P("fixed.mrk.json") + " --transform " + P("T.json"));
  EXPECT_EQ(bad.code, 3) << bad.output;
  EXPECT_NE(bad.output.find("two.mrk.json"), std::string::npos) << bad.output;
  EXPECT_NE(bad.output.find("at least 3"), std::string::npos) << bad.output;
  EXPECT_EQ(CountFiles(), before + 1);  // two.mrk.json only
}

// On two noisy 40000-point scans ICP's last sample grows to every point, and the report says what sampling
// still adds to the pose's sd (nothing); --pose-sd-fraction 0 keeps it at 30000 points; a fraction outside
// [0, 1) is a usage error. Each level reports its wall time.
TEST_F(RegisterCommand, PoseSdFractionDecidesHowFarTheLastSampleGrows) {
  std::mt19937_64 rng(5);
  const Rigid3 T_true = testing::RandomPose(&rng, 10.0, 30.0, Eigen::Vector3d(0, 100, 160));
  WriteScan("fixed", Rigid3::Identity(), 11, dir_, 40000);
  WriteScan("moving", T_true, 12, dir_, 40000);
  auto run = [&](const std::string& extra) { return RegisterMovingToFixed(extra); };
  auto last_points = [&] {
    const nlohmann::json report = Report();
    return std::pair{report["icp"]["levels"].back()["source_points"].get<int>(),
                     report["icp"]["sampling_sd_mm"].get<double>()};
  };
  CliRun r = run("");
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_EQ(last_points().first, 40000);
  EXPECT_EQ(last_points().second, 0.0);
  // Each level's wall time is reported; together they are part of ICP's.
  const nlohmann::json report = Report();
  double levels_s = 0.0;
  for (const auto& level : report["icp"]["levels"]) {
    EXPECT_GE(level["seconds"].get<double>(), 0.0);
    levels_s += level["seconds"].get<double>();
  }
  EXPECT_GT(levels_s, 0.0);
  EXPECT_LE(levels_s, report["timings_s"]["icp"].get<double>());
  r = run(" --pose-sd-fraction 0");
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_EQ(last_points().first, 30000);
  EXPECT_GT(last_points().second, 0.0);
  r = run(" --pose-sd-fraction 1.5");
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find("target_pose_sd_fraction"), std::string::npos) << r.output;
}

// --plane-points sets how many fixed points ICP's plane passes through: on two scans with 0.2 mm noise the
// residual scale is the two noises', 0.2 sqrt(2) mm, with the nearest point's own plane, and the fixed
// scan's share a quarter as large, 0.2 sqrt(1 + 1/4) mm, through four; both recover the pose; 0 or 5 is a
// usage error.
TEST_F(RegisterCommand, PlanePointsAverageTheFixedScansNoise) {
  std::mt19937_64 rng(7);
  const Rigid3 T_true = testing::RandomPose(&rng, 10.0, 30.0, Eigen::Vector3d(0, 100, 160));
  WriteScan("fixed", Rigid3::Identity(), 21, dir_, 30000);
  WriteScan("moving", T_true, 22, dir_, 30000);
  auto run = [&](const std::string& extra) { return RegisterMovingToFixed(extra); };
  auto scale = [&] { return Report()["icp"]["residual_scale_mm"].get<double>(); };
  for (const auto& [flag, expected] : {std::pair{std::string(" --plane-points 1"), 0.2 * std::sqrt(2.0)},
                                       std::pair{std::string(""), 0.2 * std::sqrt(1.25)}}) {
    SCOPED_TRACE(flag.empty() ? "default" : flag);
    const CliRun r = run(flag);
    ASSERT_EQ(r.code, 0) << r.output;
    EXPECT_NEAR(scale(), expected, 0.02);
    const PoseError e = ComparePoses(ReadTransformJson(P("T.json")), Similarity3::FromRigid(T_true),
                                     Eigen::Vector3d(0, 100, 160));
    EXPECT_LT(e.rotation_deg, 0.05);
    EXPECT_LT(e.translation_mm, 0.1);
  }
  for (const std::string bad : {"0", "5"}) {
    const CliRun r = run(" --plane-points " + bad);
    EXPECT_EQ(r.code, 2) << r.output;
    EXPECT_NE(r.output.find("--plane-points"), std::string::npos) << r.output;
  }
}

// A cohort folder of three scans of one chest at known poses: to the reference (the second file) and
// groupwise, every scan's transform into the reference frame to 0.05 degrees and 0.1 mm, and a summary.
TEST_F(RegisterCommand, CohortWritesEveryTransformAndASummary) {
  const fs::path scans = dir_ / "scans";
  fs::create_directories(scans);
  std::mt19937_64 rng(5);
  std::vector<Rigid3> T_world(3);
  for (int i = 0; i < 3; ++i) {
    T_world[i] = i == 0 ? Rigid3(Rigid3::Identity())
                        : testing::RandomPose(&rng, 15.0, 80.0, Eigen::Vector3d(0, 100, 160));
    WriteScan("scan" + std::to_string(i), T_world[i], 10 + static_cast<std::uint64_t>(i), scans);
  }
  for (const std::string mode : {"", " --groupwise"}) {
    const fs::path out = dir_ / ("aligned" + std::to_string(mode.size()));
    const CliRun r = Pectus("register --cohort " + scans.string() + " --reference scan1.ply -o " +
                            out.string() + mode + " --quiet");
    ASSERT_EQ(r.code, 0) << mode << ": " << r.output;
    nlohmann::json summary;
    std::ifstream(out / "summary.json") >> summary;
    EXPECT_EQ(summary["reference"], "scan1");
    EXPECT_TRUE(summary["all_succeeded"].get<bool>());
    ASSERT_EQ(summary["scans"].size(), 3u);
    for (int i = 0; i < 3; ++i) {
      const std::string name = "scan" + std::to_string(i);
      const Similarity3 T = ReadTransformJson(out / (name + ".T.json"));
      const PointCloud c = ReadPointCloud(scans / (name + ".ply"));
      const Similarity3 truth = Similarity3::FromRigid(T_world[1].inverse() * T_world[i]);
      const PoseError e = ComparePoses(T, truth, c.positions.colwise().mean().transpose());
      EXPECT_LT(e.rotation_deg, 0.05) << mode << " " << name;
      EXPECT_LT(e.translation_mm, 0.1) << mode << " " << name;
    }
  }
}

}  // namespace
}  // namespace pectus
