// PLY: round trips through the writer, hand-written files (big endian, polygons, other elements, CRLF)
// and the real Stanford bunny sweeps. Malformed files: ply_io_malformed_test.cc.
#include <gtest/gtest.h>

#include <cstdint>
#include <filesystem>
#include <string>

#include "shape/core/error.h"
#include "shape/io/format_parsers.h"
#include "shape/io/mesh_io.h"
#include "tests/shape/io/ply_test_util.h"
#include "tests/support/require_shared_data.h"

namespace pectus {
namespace {

using namespace pectus::testing;  // NOLINT: the PLY test helpers

TEST(PlyRoundTrip, BinaryLittleEndianIsExact) {
  const TriangleMesh mesh = MakeMesh();
  const std::string bytes = ToPly(mesh, true, "scan of a test object");
  EXPECT_NE(bytes.find("format binary_little_endian 1.0\n"), std::string::npos);
  EXPECT_NE(bytes.find("property list uchar int vertex_indices\n"), std::string::npos);
  FileSummary summary;
  ExpectSameMesh(mesh, ParsePly(bytes, "roundtrip.ply", &summary));
  EXPECT_EQ(summary.format, "ply");
  EXPECT_EQ(summary.encoding, "binary_little_endian");
  ASSERT_EQ(summary.comments.size(), 2u);
  EXPECT_EQ(summary.comments[0], "scan of a test object");
  EXPECT_EQ(summary.comments[1], "pectus units mm");
  ASSERT_EQ(summary.elements.size(), 2u);
  EXPECT_EQ(summary.elements[0].count, 6);
  EXPECT_EQ(summary.elements[0].properties,
            (std::vector<std::string>{"float x", "float y", "float z", "float nx", "float ny", "float nz",
                                      "uchar red", "uchar green", "uchar blue", "float confidence",
                                      "float intensity"}));
  EXPECT_EQ(summary.elements[1].count, 4);
}

TEST(PlyRoundTrip, AsciiIsExact) {
  const TriangleMesh mesh = MakeMesh();
  const std::string bytes = ToPly(mesh, false);
  EXPECT_NE(bytes.find("format ascii 1.0\n"), std::string::npos);
  ExpectSameMesh(mesh, ParsePly(bytes, "roundtrip_ascii.ply"));
}

TEST(PlyRoundTrip, FarFromOriginKeepsDoublePrecision) {
  TriangleMesh mesh;
  mesh.vertices.positions.resize(2, 3);
  mesh.vertices.positions << 6378137.125, -1e6 + 0.001, 3.0, 1.0 / 3.0, 2.0, 123456.789;
  mesh.faces.resize(0, 3);
  for (bool binary : {true, false}) {
    const std::string bytes = ToPly(mesh, binary);
    EXPECT_NE(bytes.find("property double x\n"), std::string::npos);
    EXPECT_EQ(bytes.find("element face"), std::string::npos);  // a point cloud
    ExpectSameMesh(mesh, ParsePly(bytes, "far.ply"));
  }
}

TEST(ParsePly, ReadsHandWrittenBigEndian) {
  const TriangleMesh mesh = MakeMesh();
  std::string bytes =
      "ply\nformat binary_big_endian 1.0\ncomment written by hand\nelement vertex 6\n"
      "property float x\nproperty float y\nproperty float z\nproperty float nx\nproperty float ny\n"
      "property float nz\nproperty uchar red\nproperty uchar green\nproperty uchar blue\nproperty uchar "
      "alpha\n"
      "property double confidence\nproperty float32 intensity\n"
      "element face 3\nproperty uchar flags\nproperty list uchar uint vertex_indices\nend_header\n";
  const PointCloud& v = mesh.vertices;
  for (int i = 0; i < 6; ++i) {
    for (int k = 0; k < 3; ++k) PutBigEndian(&bytes, static_cast<float>(v.positions(i, k)));
    for (int k = 0; k < 3; ++k) PutBigEndian(&bytes, static_cast<float>(v.normals(i, k)));
    for (int k = 0; k < 3; ++k) bytes += static_cast<char>(v.colors(i, k));
    bytes += '\xff';  // alpha, ignored
    PutBigEndian(&bytes, v.scalars.at("confidence")(i));
    PutBigEndian(&bytes, static_cast<float>(v.scalars.at("intensity")(i)));
  }
  // Two triangles and a quad (fanned), each after a one-byte flag that is not kept.
  bytes += '\x01';
  bytes += '\x03';
  for (std::uint32_t index : {0u, 1u, 2u}) PutBigEndian(&bytes, index);
  bytes += '\x02';
  bytes += '\x03';
  for (std::uint32_t index : {0u, 2u, 3u}) PutBigEndian(&bytes, index);
  bytes += '\x03';
  bytes += '\x04';
  for (std::uint32_t index : {3u, 4u, 5u, 1u}) PutBigEndian(&bytes, index);
  bytes += "trailing bytes after the last element are allowed";

  TriangleMesh expected = mesh;
  expected.faces.resize(4, 3);
  expected.faces << 0, 1, 2, 0, 2, 3, 3, 4, 5, 3, 5, 1;
  ExpectSameMesh(expected, ParsePly(bytes, "big_endian.ply"));
}

TEST(ParsePly, FansPolygonsIntoTriangles) {
  const std::string bytes =
      "ply\nformat ascii 1.0\nelement vertex 5\nproperty float x\nproperty float y\nproperty float z\n"
      "element face 2\nproperty list uchar int vertex_index\nend_header\n"
      "0 0 0\n1 0 0\n1 1 0\n0 1 0\n0.5 2 0\n4 0 1 2 3\n3 3 2 4\n";
  const TriangleMesh mesh = ParsePly(bytes, "quad.ply");
  Faces3 expected(3, 3);
  expected << 0, 1, 2, 0, 2, 3, 3, 2, 4;
  EXPECT_EQ(mesh.faces, expected);
  EXPECT_EQ(mesh.vertices.positions(4, 0), 0.5);
  EXPECT_FALSE(mesh.vertices.has_normals());
  EXPECT_TRUE(mesh.vertices.scalars.empty());
}

TEST(ParsePly, SkipsOtherElementsInAscii) {
  const std::string bytes =
      "ply\nformat ascii 1.0\nobj_info num_cols 2\nelement camera 1\nproperty float focal\n"
      "element range_grid 4\nproperty list uchar int vertex_indices\n"
      "element vertex 2\nproperty float x\nproperty float y\nproperty float z\nproperty float confidence\n"
      "element extra 2\nproperty list uchar float values\nproperty int id\nend_header\n"
      "35.5\n1 0\n0\n\n2 0 1\n0\n"
      "1.5 -2.25 3\t0.75\n-4 5e2 6.125 1\n"
      "3 1 2 3 7\n0 8\n";
  FileSummary summary;
  const TriangleMesh mesh = ParsePly(bytes, "grid.ply", &summary);
  Points3 expected(2, 3);
  expected << 1.5, -2.25, 3, -4, 500, 6.125;
  EXPECT_EQ(mesh.vertices.positions, expected);
  EXPECT_EQ(mesh.vertices.scalars.at("confidence"), Eigen::Vector2d(0.75, 1.0));
  EXPECT_EQ(mesh.num_faces(), 0);
  ASSERT_EQ(summary.elements.size(), 4u);
  EXPECT_EQ(summary.elements[1].name, "range_grid");
  EXPECT_EQ(summary.elements[1].properties, std::vector<std::string>{"list uchar int vertex_indices"});
  EXPECT_EQ(summary.elements[3].properties, (std::vector<std::string>{"list uchar float values", "int id"}));
  EXPECT_EQ(summary.comments, std::vector<std::string>{"obj_info num_cols 2"});
}

TEST(ParsePly, SkipsOtherElementsInBinary) {
  std::string bytes =
      "ply\nformat binary_little_endian 1.0\nelement range_grid 3\nproperty list uchar int vertex_indices\n"
      "element vertex 2\nproperty double x\nproperty double y\nproperty double z\n"
      "property list uchar short tags\n"
      "element extra 2\nproperty int id\nproperty list int float values\nend_header\n";
  bytes += '\x01';
  PutLittleEndian<std::int32_t>(&bytes, 0);
  bytes += '\x00';
  bytes += '\x02';
  PutLittleEndian<std::int32_t>(&bytes, 0);
  PutLittleEndian<std::int32_t>(&bytes, 1);
  // Vertices with a list property take the record-by-record path.
  for (double value : {1.0 / 3.0, -2.5, 1e-300}) PutLittleEndian(&bytes, value);
  bytes += '\x02';
  PutLittleEndian<std::int16_t>(&bytes, 5);
  PutLittleEndian<std::int16_t>(&bytes, 6);
  for (double value : {4.0, 5.0, 6.0}) PutLittleEndian(&bytes, value);
  bytes += '\x00';
  for (int id = 0; id < 2; ++id) {
    PutLittleEndian<std::int32_t>(&bytes, id);
    PutLittleEndian<std::int32_t>(&bytes, 1);
    PutLittleEndian(&bytes, 2.5f);
  }
  const TriangleMesh mesh = ParsePly(bytes, "grid.ply");
  Points3 expected(2, 3);
  expected << 1.0 / 3.0, -2.5, 1e-300, 4, 5, 6;
  EXPECT_EQ(mesh.vertices.positions, expected);
  EXPECT_TRUE(mesh.vertices.scalars.empty());
  // One byte short in the last element is an error.
  ExpectBadInput(std::string_view(bytes).substr(0, bytes.size() - 1), "short.ply", "ends after 1 of 2");
}

TEST(ParsePly, AcceptsCrLfFloatColoursAndPlusSigns) {
  const std::string bytes =
      "ply\r\nformat ascii 1.0\r\ncomment made on windows\r\nelement vertex 2\r\nproperty float32 x\r\n"
      "property float32 y\r\nproperty float32 z\r\nproperty float red\r\nproperty float green\r\n"
      "property float blue\r\nend_header\r\n"
      "0.1 +2 -3e-1 1 0.5 0\r\n4 5 6 0 0.2 2\r\n";
  FileSummary summary;
  const TriangleMesh mesh = ParsePly(bytes, "crlf.ply", &summary);
  EXPECT_EQ(summary.comments, std::vector<std::string>{"made on windows"});
  // Values of float properties are read as float.
  EXPECT_EQ(mesh.vertices.positions(0, 0), static_cast<double>(0.1f));
  EXPECT_EQ(mesh.vertices.positions(0, 1), 2.0);
  EXPECT_EQ(mesh.vertices.positions(0, 2), static_cast<double>(-0.3f));
  ASSERT_TRUE(mesh.vertices.has_colors());
  EXPECT_EQ(mesh.vertices.colors.row(0), (Eigen::Matrix<std::uint8_t, 1, 3>(255, 128, 0)));
  EXPECT_EQ(mesh.vertices.colors.row(1), (Eigen::Matrix<std::uint8_t, 1, 3>(0, 51, 255)));
}

TEST(ReadMesh, ReadsAllStanfordBunnySweeps) {
  PECTUS_REQUIRE_SHARED_FILE(testing_support::kBunnyConf);
  const std::filesystem::path folder = testing_support::BunnyDirectory();
  const std::pair<const char*, Eigen::Index> sweeps[] = {
      {"bun000", 40256}, {"bun045", 40097}, {"bun090", 30379}, {"bun180", 40251},   {"bun270", 31701},
      {"bun315", 35336}, {"chin", 37738},   {"top2", 38298},   {"ear_back", 32193}, {"top3", 36023}};
  ReadOptions options;
  options.input_units = LengthUnit::kMetre;
  for (const auto& [stem, count] : sweeps) {
    FileSummary summary;
    const TriangleMesh mesh = ReadMesh(folder / (std::string(stem) + ".ply"), options, &summary);
    EXPECT_EQ(mesh.num_vertices(), count) << stem;
    EXPECT_EQ(mesh.num_faces(), 0) << stem;
    EXPECT_EQ(summary.encoding, "ascii") << stem;
    ASSERT_EQ(summary.elements.size(), 2u) << stem;
    EXPECT_EQ(summary.elements[1].name, "range_grid") << stem;
    EXPECT_EQ(summary.elements[1].count, 204800) << stem;
    // The bunny is about 15 cm across.
    const double size = ComputeBounds(mesh.vertices.positions).extent().maxCoeff();
    EXPECT_GT(size, 80.0) << stem;
    EXPECT_LT(size, 200.0) << stem;
  }
  // The first vertex of bun000 is "-0.06325 0.0359793 0.0420873" (float, metres).
  const TriangleMesh bun000 = ReadMesh(folder / "bun000.ply", options);
  EXPECT_EQ(bun000.vertices.positions(0, 0), static_cast<double>(-0.06325f) * 1000.0);
  EXPECT_EQ(bun000.vertices.positions(0, 2), static_cast<double>(0.0420873f) * 1000.0);
}

}  // namespace
}  // namespace pectus
