#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <string_view>

#include "shape/core/error.h"
#include "shape/io/format_parsers.h"
#include "shape/io/mesh_io.h"
#include "tests/support/require_shared_data.h"

namespace pectus {
namespace {

/// A small mesh whose every value is exactly representable as float (and colours as uchar):
/// 6 vertices with normals, colours and two scalars, 4 triangles.
TriangleMesh MakeMesh() {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> coordinate(-300.0f, 300.0f), unit(-1.0f, 1.0f), score(0.0f, 1.0f);
  TriangleMesh mesh;
  const int n = 6;
  mesh.vertices.positions.resize(n, 3);
  mesh.vertices.normals.resize(n, 3);
  mesh.vertices.colors.resize(n, 3);
  Eigen::VectorXd confidence(n), intensity(n);
  for (int i = 0; i < n; ++i) {
    for (int k = 0; k < 3; ++k) {
      mesh.vertices.positions(i, k) = coordinate(rng);
      mesh.vertices.normals(i, k) = unit(rng);
      mesh.vertices.colors(i, k) = static_cast<std::uint8_t>(40 * i + 7 * k);
    }
    confidence(i) = score(rng);
    intensity(i) = 1000.0f * score(rng);
  }
  mesh.vertices.scalars["confidence"] = confidence;
  mesh.vertices.scalars["intensity"] = intensity;
  mesh.faces.resize(4, 3);
  mesh.faces << 0, 1, 2, 0, 2, 3, 3, 4, 5, 5, 1, 0;
  return mesh;
}

std::string ToPly(const TriangleMesh& mesh, bool binary, const std::string& comment = "") {
  std::ostringstream out;
  WriteOptions options;
  options.binary = binary;
  options.comment = comment;
  WritePly(out, mesh, options);
  return out.str();
}

void ExpectSameMesh(const TriangleMesh& expected, const TriangleMesh& actual) {
  ASSERT_EQ(actual.num_vertices(), expected.num_vertices());
  EXPECT_EQ(actual.vertices.positions, expected.vertices.positions);
  EXPECT_EQ(actual.vertices.normals, expected.vertices.normals);
  EXPECT_EQ(actual.vertices.colors, expected.vertices.colors);
  ASSERT_EQ(actual.vertices.scalars.size(), expected.vertices.scalars.size());
  for (const auto& [name, values] : expected.vertices.scalars) {
    ASSERT_EQ(actual.vertices.scalars.count(name), 1u) << name;
    EXPECT_EQ(actual.vertices.scalars.at(name), values) << name;
  }
  EXPECT_EQ(actual.faces, expected.faces);
}

/// Parsing `bytes` must throw Error(kBadInput) whose message names `file` and contains `phrase`.
void ExpectBadInput(std::string_view bytes, const std::string& file, const std::string& phrase) {
  try {
    ParsePly(bytes, file);
    ADD_FAILURE() << file << ": parsed without error, expected '" << phrase << "'";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::kBadInput) << e.what();
    EXPECT_NE(std::string(e.what()).find(file), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(phrase), std::string::npos) << e.what() << "\n  expected: " << phrase;
  }
}

/// The line number an error reports, or -1 if parsing succeeded.
std::int64_t ErrorLine(std::string_view bytes) {
  try {
    ParsePly(bytes, "line.ply");
  } catch (const Error& e) {
    return e.line();
  }
  return -1;
}

template <typename T>
void PutBigEndian(std::string* out, T value) {
  char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));
  if constexpr (std::endian::native == std::endian::little) std::reverse(bytes, bytes + sizeof(T));
  out->append(bytes, sizeof(T));
}

template <typename T>
void PutLittleEndian(std::string* out, T value) {
  char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));
  if constexpr (std::endian::native == std::endian::big) std::reverse(bytes, bytes + sizeof(T));
  out->append(bytes, sizeof(T));
}

const char kAsciiCloud[] =
    "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
    "end_header\n";

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
      "property float nz\nproperty uchar red\nproperty uchar green\nproperty uchar blue\nproperty uchar alpha\n"
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
  EXPECT_EQ(summary.elements[3].properties,
            (std::vector<std::string>{"list uchar float values", "int id"}));
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
      {"bun000", 40256}, {"bun045", 40097}, {"bun090", 30379}, {"bun180", 40251},     {"bun270", 31701},
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

// ------------------------------------------------------------------------------------------------
// Malformed files: each is Error(kBadInput) naming the file and what is wrong.

TEST(PlyMalformed, EmptyFile) { ExpectBadInput("", "empty.ply", "file is empty"); }

TEST(PlyMalformed, NotAPly) { ExpectBadInput("solid cube\nfacet normal 0 0 1\n", "cube.ply", "not a PLY file"); }

TEST(PlyMalformed, GarbageAfterMagic) {
  ExpectBadInput(std::string("ply\n\x01\x02\xfe garbage\nformat ascii 1.0\nend_header\n"), "garbage.ply",
                 "unknown header line '?");
  EXPECT_EQ(ErrorLine(std::string("ply\nformat ascii 1.0\n\x7f\x45LF\n")), 3);
}

TEST(PlyMalformed, MissingEndHeader) {
  ExpectBadInput("ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n", "noend.ply", "missing end_header");
}

TEST(PlyMalformed, UnknownFormat) {
  ExpectBadInput("ply\nformat binary_middle_endian 1.0\nend_header\n", "format.ply",
                 "unknown format 'binary_middle_endian'");
}

TEST(PlyMalformed, UnknownPropertyType) {
  const std::string bytes =
      "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float128 y\nproperty float z\n"
      "end_header\n0 0 0\n";
  ExpectBadInput(bytes, "type.ply", "unknown property type 'float128' for property 'y'");
  EXPECT_EQ(ErrorLine(bytes), 5);
}

TEST(PlyMalformed, VertexWithoutZ) {
  ExpectBadInput("ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nend_header\n0 0\n",
                 "noz.ply", "no scalar property 'z'");
}

TEST(PlyMalformed, TruncatedBinary) {
  TriangleMesh cloud = MakeMesh();
  cloud.faces.resize(0, 3);
  const std::string bytes = ToPly(cloud, true);
  const std::size_t record = 12 + 12 + 3 + 8;
  ExpectBadInput(std::string_view(bytes).substr(0, bytes.size() - record - 5), "cut.ply", "ends after 4 of 6 vertices");
  const TriangleMesh mesh = MakeMesh();
  const std::string with_faces = ToPly(mesh, true);
  ExpectBadInput(std::string_view(with_faces).substr(0, with_faces.size() - 2), "cut_faces.ply",
                 "ends after 3 of 4 faces");
}

TEST(PlyMalformed, AsciiHeaderCountTooLarge) {
  const std::string bytes = std::string(kAsciiCloud) + "1 2 3\n4 5 6\n";
  ExpectBadInput(bytes, "few.ply", "file ends after 2 of 3 vertices");
}

TEST(PlyMalformed, AsciiHeaderCountTooSmall) {
  const std::string bytes = std::string(kAsciiCloud) + "1 2 3\n4 5 6\n7 8 9\n10 11 12\n\n";
  ExpectBadInput(bytes, "many.ply", "more data lines than the header declares");
  EXPECT_EQ(ErrorLine(bytes), 11);
}

TEST(PlyMalformed, NonNumericToken) {
  const std::string bytes = std::string(kAsciiCloud) + "1 2 3\n4 five 6\n7 8 9\n";
  ExpectBadInput(bytes, "text.ply", "property 'y' of vertex 1 is not a number: 'five'");
  EXPECT_EQ(ErrorLine(bytes), 9);
  ExpectBadInput(std::string(kAsciiCloud) + "1 2 3\n4 5\n7 8 9\n", "short.ply", "too few values");
  ExpectBadInput(std::string(kAsciiCloud) + "1 2 3\n4 5 6 7\n7 8 9\n", "long.ply", "more values");
}

TEST(PlyMalformed, NanAndInfCoordinates) {
  ExpectBadInput(std::string(kAsciiCloud) + "1 2 3\n4 nan 6\n7 8 9\n", "nan.ply",
                 "vertex 1 has a non-finite coordinate");
  ExpectBadInput(std::string(kAsciiCloud) + "1 2 3\n4 5 6\n-inf 8 9\n", "inf.ply",
                 "vertex 2 has a non-finite coordinate");
  TriangleMesh mesh = MakeMesh();
  mesh.vertices.positions(3, 1) = std::numeric_limits<double>::quiet_NaN();
  ExpectBadInput(ToPly(mesh, true), "nan_binary.ply", "vertex 3 has a non-finite coordinate");
  mesh.vertices.positions(3, 1) = std::numeric_limits<double>::infinity();
  ExpectBadInput(ToPly(mesh, true), "inf_binary.ply", "vertex 3 has a non-finite coordinate");
}

TEST(PlyMalformed, HugeCountInTinyFile) {
  std::string binary =
      "ply\nformat binary_little_endian 1.0\nelement vertex 2000000000\nproperty float x\nproperty float y\n"
      "property float z\nend_header\n";
  const std::size_t fit = (1024 - binary.size()) / 12;
  binary.resize(1024, '\0');
  ExpectBadInput(binary, "huge_binary.ply", "ends after " + std::to_string(fit) + " of 2000000000 vertices");
  std::string ascii =
      "ply\nformat ascii 1.0\nelement vertex 2000000000\nproperty float x\nproperty float y\n"
      "property float z\nend_header\n";
  while (ascii.size() < 1024) ascii += "1 2 3\n";
  ExpectBadInput(ascii, "huge_ascii.ply", "declares 2000000000 vertices but only");
  ExpectBadInput(
      "ply\nformat binary_big_endian 1.0\nelement vertex 0\nproperty float x\nproperty float y\nproperty float z\n"
      "element face 1000000000000\nproperty list uchar int vertex_indices\nend_header\n\x03",
      "huge_faces.ply", "ends after 0 of 1000000000000 faces");
}

TEST(PlyMalformed, FaceIndexOutOfRange) {
  const std::string header =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
      "element face 2\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
  ExpectBadInput(header + "3 0 1 7\n", "index.ply", "face 1 refers to vertex 7 but there are 3 vertices");
  EXPECT_EQ(ErrorLine(header + "3 0 1 7\n"), 14);
  ExpectBadInput(header + "3 0 -1 2\n", "negative.ply", "face 1 refers to vertex -1");
  ExpectBadInput(header + "2 0 1\n", "edge.ply", "face 1 has 2 vertices (at least 3 needed)");
  ExpectBadInput(header + "-4 0 1 2\n", "count.ply", "face 1 has -4 vertices");
  ExpectBadInput(header + "300 0 1 2\n", "long.ply", "index 3 of face 1 (it lists 300)");
  TriangleMesh mesh = MakeMesh();
  mesh.faces(2, 1) = 6;
  ExpectBadInput(ToPly(mesh, true), "index_binary.ply", "face 2 refers to vertex 6 but there are 6 vertices");
}

TEST(PlyMalformed, BinaryListCounts) {
  std::string bytes =
      "ply\nformat binary_little_endian 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
      "property float z\nelement face 1\nproperty list int int vertex_indices\nend_header\n";
  for (float value : {0.0f, 0.0f, 0.0f}) PutLittleEndian(&bytes, value);
  std::string negative = bytes;
  PutLittleEndian<std::int32_t>(&negative, -5);
  negative.append(12, '\0');
  ExpectBadInput(negative, "negative.ply", "negative list length -5");
  std::string huge = bytes;
  PutLittleEndian<std::int32_t>(&huge, 2000000000);
  huge.append(12, '\0');
  ExpectBadInput(huge, "huge_list.ply", "ends after 0 of 1 faces");
}

// Every prefix of a valid file, and files with single bytes changed, either parse or throw Error.
TEST(PlyMalformed, PrefixesAndByteFlipsNeverCrash) {
  const TriangleMesh mesh = MakeMesh();
  std::mt19937 rng(11);
  for (bool binary : {true, false}) {
    const std::string bytes = ToPly(mesh, binary);
    for (std::size_t size = 0; size < bytes.size(); ++size) {
      // A copy of exactly `size` bytes, so that ASan sees any read past the end.
      const std::unique_ptr<char[]> copy(new char[size + 1]);
      std::memcpy(copy.get(), bytes.data(), size);
      try {
        ParsePly(std::string_view(copy.get(), size), "prefix.ply").Validate("prefix.ply");
      } catch (const Error& e) {
        EXPECT_EQ(e.kind(), ErrorKind::kBadInput);
      }
    }
    for (int trial = 0; trial < 2000; ++trial) {
      std::string mutated = bytes;
      for (int k = 0; k < 3; ++k) mutated[rng() % mutated.size()] = static_cast<char>(rng());
      try {
        ParsePly(mutated, "mutated.ply").Validate("mutated.ply");
      } catch (const Error& e) {
        EXPECT_EQ(e.kind(), ErrorKind::kBadInput);
      }
    }
  }
}

}  // namespace
}  // namespace pectus
