// PLY: every malformed file is Error(kBadInput) naming the file and what is wrong; prefixes and byte
// flips of valid files never crash. Well-formed files: ply_io_test.cc.
#include <gtest/gtest.h>

#include <cstdint>
#include <limits>
#include <random>
#include <string>

#include "shape/core/error.h"
#include "shape/io/format_parsers.h"
#include "tests/shape/io/ply_test_util.h"

namespace pectus {
namespace {

using namespace pectus::testing;  // NOLINT: the PLY test helpers

// ------------------------------------------------------------------------------------------------
// Malformed files: each is Error(kBadInput) naming the file and what is wrong.

TEST(PlyMalformed, EmptyFile) { ExpectBadInput("", "empty.ply", "file is empty"); }

TEST(PlyMalformed, NotAPly) {
  ExpectBadInput("solid cube\nfacet normal 0 0 1\n", "cube.ply", "not a PLY file");
}

TEST(PlyMalformed, GarbageAfterMagic) {
  ExpectBadInput(std::string("ply\n\x01\x02\xfe garbage\nformat ascii 1.0\nend_header\n"), "garbage.ply",
                 "unknown header line '?");
  EXPECT_EQ(ErrorLine(std::string("ply\nformat ascii 1.0\n\x7f\x45LF\n")), 3);
}

TEST(PlyMalformed, MissingEndHeader) {
  ExpectBadInput("ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n", "noend.ply",
                 "missing end_header");
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
  ExpectBadInput(
      "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nend_header\n0 0\n",
      "noz.ply", "no scalar property 'z'");
}

TEST(PlyMalformed, TruncatedBinary) {
  TriangleMesh cloud = MakeMesh();
  cloud.faces.resize(0, 3);
  const std::string bytes = ToPly(cloud, true);
  const std::size_t record = 12 + 12 + 3 + 8;
  ExpectBadInput(std::string_view(bytes).substr(0, bytes.size() - record - 5), "cut.ply",
                 "ends after 4 of 6 vertices");
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
      "ply\nformat binary_big_endian 1.0\nelement vertex 0\nproperty float x\nproperty float y\nproperty "
      "float z\n"
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
