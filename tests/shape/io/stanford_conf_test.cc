#include "shape/io/stanford_conf.h"

#include <gtest/gtest.h>

#include <cmath>

#include "shape/core/error.h"
#include "tests/shape/io/io_test_util.h"
#include "tests/support/require_shared_data.h"

namespace pectus {
namespace {

using testing::ThrowsBadInput;

const std::filesystem::path kBunnyConf = testing_support::SharedPath(testing_support::kBunnyConf);

// The rotation matrix of the unit quaternion (x, y, z, w), written out (not through Eigen) so that the
// test checks the convention independently of the implementation.
Eigen::Matrix3d RotationOf(double x, double y, double z, double w) {
  const double n = std::sqrt(x * x + y * y + z * z + w * w);
  x /= n, y /= n, z /= n, w /= n;
  Eigen::Matrix3d R;
  R << 1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w),  //
      2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w),   //
      2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y);
  return R;
}

TEST(StanfordConf, ReadsTheRealBunnyAlignment) {
  PECTUS_REQUIRE_SHARED_FILE(testing_support::kBunnyConf);
  const std::vector<ScanPose> poses = ReadStanfordConf(kBunnyConf);
  ASSERT_EQ(poses.size(), 10u);
  const std::vector<std::string> files = {"bun000.ply", "bun045.ply",  "bun090.ply", "bun180.ply",
                                          "bun270.ply", "top2.ply",    "top3.ply",   "bun315.ply",
                                          "chin.ply",   "ear_back.ply"};
  for (std::size_t i = 0; i < files.size(); ++i) EXPECT_EQ(poses[i].file, files[i]);
  EXPECT_TRUE(poses[0].T_common_scan.matrix().isIdentity(0.0));

  // bmesh bun045.ply -0.0520211 -0.000383981 -0.0109223 0.00548449 -0.294635 -0.0038555 0.955586
  // p_common = R(q)^T p_scan + t.
  const Eigen::Matrix3d R = RotationOf(0.00548449, -0.294635, -0.0038555, 0.955586);
  const Eigen::Vector3d t(-0.0520211, -0.000383981, -0.0109223);
  for (const Eigen::Vector3d& p : {Eigen::Vector3d(0.01, 0.02, 0.03), Eigen::Vector3d(-0.07, 0.15, -0.02)}) {
    const Eigen::Vector3d expected = R.transpose() * p + t;
    EXPECT_LT((poses[1].T_common_scan * p - expected).norm(), 1e-12);
  }
  // About 34 degrees about (nearly) the y axis.
  EXPECT_NEAR(Eigen::AngleAxisd(poses[1].T_common_scan.linear()).angle(), 2 * std::acos(0.955586), 1e-5);
}

TEST(StanfordConf, WriteThenReadRecoversThePoses) {
  PECTUS_REQUIRE_SHARED_FILE(testing_support::kBunnyConf);
  std::vector<ScanPose> poses;
  for (int i = 0; i < 5; ++i) {
    ScanPose pose{"scan_" + std::to_string(i) + ".ply", Rigid3::Identity()};
    pose.T_common_scan.linear() =
        Eigen::AngleAxisd(0.3 + 0.7 * i, Eigen::Vector3d(1.0, -0.5 * i, 0.25).normalized())
            .toRotationMatrix();
    pose.T_common_scan.translation() = Eigen::Vector3d(1.0 / 3 + i, -123.456789 * i, 1e-7 * (i + 1));
    poses.push_back(pose);
  }
  const testing::TempDir dir;
  WriteStanfordConf(dir / "out.conf", poses);
  const std::vector<ScanPose> back = ReadStanfordConf(dir / "out.conf");
  ASSERT_EQ(back.size(), poses.size());
  for (std::size_t i = 0; i < poses.size(); ++i) {
    EXPECT_EQ(back[i].file, poses[i].file);
    EXPECT_LT((back[i].T_common_scan.matrix() - poses[i].T_common_scan.matrix()).cwiseAbs().maxCoeff(),
              1e-12);
  }
  // The real file survives a write and read too.
  const std::vector<ScanPose> bunny = ReadStanfordConf(kBunnyConf);
  WriteStanfordConf(dir / "bun.conf", bunny);
  const std::vector<ScanPose> bunny_back = ReadStanfordConf(dir / "bun.conf");
  for (std::size_t i = 0; i < bunny.size(); ++i) {
    EXPECT_LT((bunny_back[i].T_common_scan.matrix() - bunny[i].T_common_scan.matrix()).cwiseAbs().maxCoeff(),
              1e-12);
  }
}

TEST(StanfordConf, CommentsCamerasAndUnnormalisedQuaternions) {
  const std::vector<ScanPose> poses = ParseStanfordConf(
      "# aligned by hand\n\ncamera 0 0 1  0 0 0 1\nbmesh a.ply 1 2 3 0 0 0 2\n\tbmesh b.ply 0 0 0 0 0 3 0\n",
      "x.conf");
  ASSERT_EQ(poses.size(), 2u);
  EXPECT_TRUE(poses[0].T_common_scan.linear().isIdentity(1e-15));
  EXPECT_EQ(poses[0].T_common_scan.translation(), Eigen::Vector3d(1, 2, 3));
  // q = z axis, 180 degrees: R = diag(-1, -1, 1).
  EXPECT_TRUE(
      poses[1].T_common_scan.linear().isApprox(Eigen::Vector3d(-1, -1, 1).asDiagonal().toDenseMatrix()));

  std::vector<ScanPose> scaled = poses;
  ScaleTranslations(1000.0, &scaled);
  EXPECT_EQ(scaled[0].T_common_scan.translation(), Eigen::Vector3d(1000, 2000, 3000));
  EXPECT_EQ(scaled[0].T_common_scan.linear(), poses[0].T_common_scan.linear());
}

TEST(StanfordConf, MalformedInputIsAnErrorNamingFileAndLine) {
  EXPECT_TRUE(ThrowsBadInput([] { ParseStanfordConf("", "e.conf"); }, "file is empty", "e.conf"));
  EXPECT_TRUE(ThrowsBadInput([] { ParseStanfordConf("camera 0 0 0 0 0 0 1\n", "c.conf"); },
                             "no 'bmesh' or 'mesh' lines", "c.conf"));
  EXPECT_TRUE(ThrowsBadInput(
      [] { ParseStanfordConf("bmesh a.ply 0 0 0 0 0 0 1\nbmesh b.ply 0 0 0 0 0 1\n", "f.conf"); }, "found 7",
      "f.conf", 2));
  EXPECT_TRUE(ThrowsBadInput([] { ParseStanfordConf("bmesh a.ply 0 0 0 0 0 0 1 9\n", "m.conf"); },
                             "8 fields after 'bmesh' (FILE tx ty tz qx qy qz qw), found 9", "m.conf", 1));
  EXPECT_TRUE(ThrowsBadInput([] { ParseStanfordConf("bmesh a.ply 0 0 0 0 0 0 0\n", "q.conf"); },
                             "quaternion (qx qy qz qw) is zero", "q.conf", 1));
  EXPECT_TRUE(ThrowsBadInput([] { ParseStanfordConf("bmesh a.ply 0 x 0 0 0 0 1\n", "n.conf"); },
                             "'x' is not a number", "n.conf", 1));
  EXPECT_TRUE(ThrowsBadInput([] { ParseStanfordConf("bmesh a.ply 0 0 0 nan 0 0 1\n", "nan.conf"); },
                             "non-finite", "nan.conf", 1));
  EXPECT_TRUE(ThrowsBadInput(
      [] { ParseStanfordConf("bmesh a.ply 0 0 0 0 0 0 1\n\nbmesh a.ply 1 0 0 0 0 0 1\n", "d.conf"); },
      "'a.ply' is listed twice (lines 1 and 3)", "d.conf", 3));
  EXPECT_TRUE(ThrowsBadInput([] { ParseStanfordConf("bmesh a.ply 0 0 0 0 0 0 1\nmesh b.ply\n", "k.conf"); },
                             "expected 8 fields after 'mesh' (FILE tx ty tz qx qy qz qw), found 1", "k.conf",
                             2));
  EXPECT_TRUE(ThrowsBadInput([] { ParseStanfordConf("bmesh a.ply 0 0 0 0 0 0 1\nscan b.ply\n", "u.conf"); },
                             "unexpected 'scan'", "u.conf", 2));
}

// A range scanner's .conf as several Stanford sets have it: a camera line, bmesh lines, mesh lines for
// extra parts (one whose file is there, one whose file was not published) and a mesh line with no file.
// Every pose whose scan is there is read, in order, with its keyword; the rest is skipped; writing keeps
// the keywords.
TEST(StanfordConf, CameraAndMeshLinesAreRead) {
  const testing::TempDir dir;
  dir.Write("front.ply", "");
  dir.Write("stand.ply", "");
  const std::filesystem::path conf = dir.Write("parts.conf",
                                               "camera 0.1 -0.2 -0.7  -0.05 0.97 -0.24 0.01\n"
                                               "bmesh front.ply 0 0 0 0 0 0 1\n"
                                               "mesh stand.ply 0.5 0 -0.25 0 0 1 0\n"
                                               "mesh base.ply 0 0 1 0 0 0 1\n"
                                               "mesh 0 0 0 0 0 0 1\n");
  const std::vector<ScanPose> poses = ReadStanfordConf(conf);
  ASSERT_EQ(poses.size(), 2u);
  EXPECT_EQ(poses[0].file, "front.ply");
  EXPECT_EQ(poses[0].keyword, "bmesh");
  EXPECT_EQ(poses[1].file, "stand.ply");
  EXPECT_EQ(poses[1].keyword, "mesh");
  EXPECT_EQ(poses[1].T_common_scan.translation(), Eigen::Vector3d(0.5, 0, -0.25));
  EXPECT_TRUE(  // q = z axis, 180 degrees
      poses[1].T_common_scan.linear().isApprox(Eigen::Vector3d(-1, -1, 1).asDiagonal().toDenseMatrix()));
  // Parsed from bytes, the mesh line whose file is missing is still a pose (no folder to look in).
  EXPECT_EQ(ParseStanfordConf("mesh base.ply 0 0 1 0 0 0 1\nmesh 0 0 0 0 0 0 1\n", "b.conf").size(), 1u);

  WriteStanfordConf(dir / "out.conf", poses);
  const std::vector<ScanPose> back = ReadStanfordConf(dir / "out.conf");
  ASSERT_EQ(back.size(), 2u);
  EXPECT_EQ(back[1].keyword, "mesh");
  EXPECT_EQ(back[1].T_common_scan.translation(), poses[1].T_common_scan.translation());
  // A .conf whose every scan is a missing mesh names itself.
  const std::filesystem::path none = dir.Write("none.conf", "mesh gone.ply 0 0 0 0 0 0 1\n");
  EXPECT_TRUE(ThrowsBadInput([&] { ReadStanfordConf(none); }, "mesh", "none.conf"));
}

}  // namespace
}  // namespace pectus
