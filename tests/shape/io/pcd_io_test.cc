// PCD is read-only in pectus: the fixtures are written with PCL itself, in all three encodings.
#include <gtest/gtest.h>
#include <pcl/io/pcd_io.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <fstream>
#include <iterator>
#include <limits>

#include "shape/core/error.h"
#include "shape/core/log.h"
#include "shape/io/format_parsers.h"
#include "shape/io/mesh_io.h"
#include "tests/shape/io/io_test_util.h"

namespace pectus {
namespace {

using testing::ThrowsBadInput;

pcl::PointCloud<pcl::PointXYZRGBNormal> MakeCloud() {
  pcl::PointCloud<pcl::PointXYZRGBNormal> cloud;
  for (int i = 0; i < 50; ++i) {
    pcl::PointXYZRGBNormal p;
    p.x = 0.5f * i;
    p.y = -100.25f + i;
    p.z = 1000.0f / (i + 1);
    p.r = static_cast<std::uint8_t>(5 * i);
    p.g = static_cast<std::uint8_t>(255 - 5 * i);
    p.b = static_cast<std::uint8_t>(i);
    const Eigen::Vector3f n = Eigen::Vector3f(1.0f, 0.1f * i, -2.0f).normalized();
    p.normal_x = n.x();
    p.normal_y = n.y();
    p.normal_z = n.z();
    p.curvature = 0.01f * i;
    cloud.push_back(p);
  }
  return cloud;
}

TEST(PcdIo, ReadsEveryEncodingThatPclWrites) {
  const auto cloud = MakeCloud();
  const testing::TempDir dir;
  const std::string ascii = (dir / "ascii.pcd").string(), binary = (dir / "binary.pcd").string(),
                    compressed = (dir / "compressed.pcd").string();
  ASSERT_EQ(pcl::io::savePCDFile(ascii, cloud, /*binary_mode=*/false), 0);
  ASSERT_EQ(pcl::io::savePCDFile(binary, cloud, /*binary_mode=*/true), 0);
  ASSERT_EQ(pcl::io::savePCDFileBinaryCompressed(compressed, cloud), 0);
  for (const auto& [path, encoding] :
       {std::pair{ascii, "ascii"}, std::pair{binary, "binary"}, std::pair{compressed, "binary_compressed"}}) {
    SCOPED_TRACE(path);
    FileSummary summary;
    const TriangleMesh mesh = ReadPcdFile(path, &summary);
    EXPECT_EQ(summary.format, "pcd");
    EXPECT_EQ(summary.encoding, encoding);
    ASSERT_EQ(summary.elements.size(), 1u);
    EXPECT_EQ(summary.elements[0].count, 50);
    const PointCloud& v = mesh.vertices;
    ASSERT_EQ(v.size(), 50);
    ASSERT_TRUE(v.has_normals());
    ASSERT_TRUE(v.has_colors());
    ASSERT_EQ(v.scalars.count("curvature"), 1u);
    EXPECT_EQ(mesh.num_faces(), 0);
    // ASCII PCD keeps floats to 8 significant digits; binary is exact.
    const double tolerance = std::string(encoding) == "ascii" ? 1e-4 : 0.0;
    for (int i = 0; i < 50; ++i) {
      const auto& p = cloud[static_cast<std::size_t>(i)];
      EXPECT_LE((v.positions.row(i) - Eigen::RowVector3d(p.x, p.y, p.z)).cwiseAbs().maxCoeff(), tolerance);
      EXPECT_LE(
          (v.normals.row(i) - Eigen::RowVector3d(p.normal_x, p.normal_y, p.normal_z)).cwiseAbs().maxCoeff(),
          1e-6);
      EXPECT_EQ(v.colors.row(i).cast<int>(), Eigen::RowVector3i(p.r, p.g, p.b));
      EXPECT_NEAR(v.scalars.at("curvature")[i], p.curvature, 1e-7);
    }
  }
  // Through the format dispatch, with units.
  const TriangleMesh scaled = ReadMesh(binary, ReadOptions{.input_units = LengthUnit::kCentimetre});
  EXPECT_FLOAT_EQ(static_cast<float>(scaled.vertices.positions(3, 1)), 10.0f * cloud[3].y);
}

TEST(PcdIo, OrganizedCloudNaNsAreLeftOutWithAWarning) {
  pcl::PointCloud<pcl::PointXYZ> cloud(4, 2);  // organized: width 4, height 2
  for (std::size_t i = 0; i < cloud.size(); ++i) cloud[i] = pcl::PointXYZ(static_cast<float>(i), 1.0f, 2.0f);
  cloud[2].x = cloud[2].y = cloud[2].z = std::numeric_limits<float>::quiet_NaN();
  cloud[5].z = std::numeric_limits<float>::quiet_NaN();
  cloud.is_dense = false;
  const testing::TempDir dir;
  const std::string path = (dir / "organized.pcd").string();
  ASSERT_EQ(pcl::io::savePCDFileBinary(path, cloud), 0);
  const bool quiet = IsQuiet();
  SetQuiet(true);
  const WarningCollector collector;
  const TriangleMesh mesh = ReadPcdFile(path);
  SetQuiet(quiet);
  ASSERT_EQ(mesh.num_vertices(), 6);
  Eigen::VectorXd kept_x(6);
  kept_x << 0, 1, 3, 4, 6, 7;
  EXPECT_EQ(mesh.vertices.positions.col(0), kept_x);
  const std::vector<std::string> warnings = collector.warnings();
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_NE(warnings[0].find("2 of 8 points"), std::string::npos) << warnings[0];
  EXPECT_NE(warnings[0].find("organized.pcd"), std::string::npos);
}

TEST(PcdIo, MalformedFilesAreErrorsNamingTheFile) {
  const testing::TempDir dir;
  EXPECT_TRUE(
      ThrowsBadInput([&] { ReadPcdFile((dir / "missing.pcd").string()); }, "no such file", "missing.pcd"));
  EXPECT_TRUE(ThrowsBadInput([&] { ReadPcdFile(dir.Write("empty.pcd", "").string()); }, "file is empty",
                             "empty.pcd"));
  EXPECT_TRUE(
      ThrowsBadInput([&] { ReadPcdFile(dir.Write("junk.pcd", "this is not a point cloud\n").string()); },
                     "PCD", "junk.pcd"));
  pcl::PointCloud<pcl::Normal> normals_only;
  normals_only.push_back(pcl::Normal(0, 0, 1));
  const std::string no_xyz = (dir / "noxyz.pcd").string();
  ASSERT_EQ(pcl::io::savePCDFileASCII(no_xyz, normals_only), 0);
  EXPECT_TRUE(ThrowsBadInput([&] { ReadPcdFile(no_xyz); }, "no x, y, z fields", "noxyz.pcd"));

  // A binary file cut short.
  auto cloud = MakeCloud();
  const std::string whole = (dir / "whole.pcd").string();
  ASSERT_EQ(pcl::io::savePCDFileBinary(whole, cloud), 0);
  const std::string bytes = [&] {
    std::ifstream in(whole, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
  }();
  const std::filesystem::path cut = dir.Write("cut.pcd", bytes.substr(0, bytes.size() - 200));
  EXPECT_TRUE(ThrowsBadInput([&] { ReadPcdFile(cut.string()); }, "PCD", "cut.pcd"));

  // Found by fuzzing: PCL's reader dereferenced a null pointer on this header (a keyword PCL does not
  // know, as it matches keywords in capitals only).
  const std::filesystem::path odd =
      dir.Write("odd.pcd", "VErSION\nFIELDS z\nSIZE 4\nPOINTS 2\nDATA ascii\n 00");
  EXPECT_TRUE(
      ThrowsBadInput([&] { ReadPcdFile(odd.string()); }, "unexpected 'VErSION' in the header", "odd.pcd", 1));
}

}  // namespace
}  // namespace pectus
