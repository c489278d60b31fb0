// The PCD reader against PCL, its peer: files written by PCL's own writer in all three encodings read back
// as PCL's own reader reads them. Built where PCL is (not in the core-only build); pcd_io_test.cc holds
// the tests on hand-written files.
#include <gtest/gtest.h>
#include <pcl/io/pcd_io.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <cmath>
#include <limits>

#include "shape/core/error.h"
#include "shape/core/log.h"
#include "shape/io/format_parsers.h"
#include "shape/io/mesh_io.h"
#include "tests/shape/io/io_test_util.h"

namespace pectus {
namespace {

TriangleMesh ReadPcd(const std::string& path, FileSummary* summary = nullptr) {
  return ReadMesh(path, ReadOptions{.warn_units = false}, summary);
}

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
    const TriangleMesh mesh = ReadPcd(path, &summary);
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
  const TriangleMesh mesh = ReadPcd(path);
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

// Writes `cloud` with PCL in each encoding, reads it back with PCL's reader and with pectus's, and checks
// that pectus returns exactly PCL's points with a finite position, in order. `check(pectus, i, pcl)` then
// compares the point type's other fields.
template <typename Point, typename Check>
void ExpectSameAsPcl(const pcl::PointCloud<Point>& cloud, const std::string& name, Check check) {
  const testing::TempDir dir;
  for (const std::string encoding : {"ascii", "binary", "binary_compressed"}) {
    SCOPED_TRACE(name + " " + encoding);
    const std::string path = (dir / (name + "_" + encoding + ".pcd")).string();
    const int status = encoding == "ascii"    ? pcl::io::savePCDFileASCII(path, cloud)
                       : encoding == "binary" ? pcl::io::savePCDFileBinary(path, cloud)
                                              : pcl::io::savePCDFileBinaryCompressed(path, cloud);
    ASSERT_EQ(status, 0);
    pcl::PointCloud<Point> theirs;
    ASSERT_EQ(pcl::io::loadPCDFile(path, theirs), 0);
    const bool quiet = IsQuiet();
    SetQuiet(true);
    FileSummary summary;
    const TriangleMesh ours = ReadPcd(path, &summary);
    SetQuiet(quiet);
    EXPECT_EQ(summary.encoding, encoding);
    EXPECT_EQ(summary.elements.at(0).count, static_cast<std::int64_t>(theirs.size()));
    EXPECT_EQ(summary.comments.at(0), "PCD version 0.7, width " + std::to_string(theirs.width) + ", height " +
                                          std::to_string(theirs.height));
    Eigen::Index j = 0;
    for (std::size_t i = 0; i < theirs.size(); ++i) {
      const Point& p = theirs[i];
      if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) continue;
      ASSERT_LT(j, ours.num_vertices());
      EXPECT_EQ(ours.vertices.positions.row(j), Eigen::RowVector3d(p.x, p.y, p.z)) << "point " << i;
      check(ours.vertices, j, p);
      ++j;
    }
    EXPECT_EQ(j, ours.num_vertices());
  }
}

// Equal, or both NaN.
bool Same(double a, float b) { return a == static_cast<double>(b) || (std::isnan(a) && std::isnan(b)); }

TEST(PcdIo, ReadsWhatPclReadsInEveryEncoding) {
  // PointXYZ: PCL's binary files carry 4 bytes of padding ("_") per point.
  pcl::PointCloud<pcl::PointXYZ> xyz;
  for (int i = 0; i < 40; ++i) xyz.push_back(pcl::PointXYZ(0.1f * i, -3.3f * i, 1e4f + 0.7f * i));
  ExpectSameAsPcl(xyz, "xyz", [](const PointCloud& v, Eigen::Index, const pcl::PointXYZ&) {
    EXPECT_FALSE(v.has_normals());
    EXPECT_TRUE(v.scalars.empty());
  });

  // PointNormal: normals and curvature, some normals NaN (PCL's normal estimation leaves them so).
  pcl::PointCloud<pcl::PointNormal> normals;
  for (int i = 0; i < 30; ++i) {
    pcl::PointNormal p;
    p.x = 1.0f / (i + 1);
    p.y = 2.0f * i;
    p.z = -7.125f;
    const Eigen::Vector3f n = Eigen::Vector3f(0.3f, 1.0f, 0.01f * i).normalized();
    p.normal_x = i % 7 == 3 ? std::numeric_limits<float>::quiet_NaN() : n.x();
    p.normal_y = n.y();
    p.normal_z = n.z();
    p.curvature = 0.001f * i;
    normals.push_back(p);
  }
  ExpectSameAsPcl(normals, "normals", [](const PointCloud& v, Eigen::Index j, const pcl::PointNormal& p) {
    ASSERT_TRUE(v.has_normals());
    EXPECT_TRUE(Same(v.normals(j, 0), p.normal_x) && Same(v.normals(j, 1), p.normal_y) &&
                Same(v.normals(j, 2), p.normal_z));
    EXPECT_EQ(v.scalars.at("curvature")[j], p.curvature);
  });

  // PointXYZRGBNormal: a packed colour (several opaque colours are NaN as a float).
  auto rgb = MakeCloud();
  rgb[4].rgba = 0xFFFFFFFFu;
  ExpectSameAsPcl(rgb, "rgb", [](const PointCloud& v, Eigen::Index j, const pcl::PointXYZRGBNormal& p) {
    ASSERT_TRUE(v.has_colors());
    EXPECT_EQ(v.colors.row(j).cast<int>(), Eigen::RowVector3i(p.r, p.g, p.b));
    EXPECT_EQ(v.scalars.at("curvature")[j], p.curvature);
  });

  // An organized cloud (width 6, height 4) with NaN gaps, as a depth camera writes it.
  pcl::PointCloud<pcl::PointXYZI> organized(6, 4);
  for (std::size_t i = 0; i < organized.size(); ++i) {
    organized[i].x = static_cast<float>(i % 6);
    organized[i].y = static_cast<float>(i / 6);
    organized[i].z = i % 5 == 2 ? std::numeric_limits<float>::quiet_NaN() : 500.0f + static_cast<float>(i);
    organized[i].intensity = 0.25f * static_cast<float>(i);
  }
  organized.is_dense = false;
  ExpectSameAsPcl(organized, "organized", [](const PointCloud& v, Eigen::Index j, const pcl::PointXYZI& p) {
    EXPECT_EQ(v.scalars.at("intensity")[j], p.intensity);
  });
}

}  // namespace
}  // namespace pectus
