#include <gtest/gtest.h>

#include <array>
#include <chrono>
#include <cstring>
#include <limits>
#include <sstream>
#include <vector>

#include "shape/core/error.h"
#include "shape/io/format_parsers.h"
#include "tests/shape/io/io_test_util.h"

namespace pectus {
namespace {

using testing::ThrowsBadInput;
using Triangle = std::array<float, 9>;

void AppendU32(std::uint32_t v, std::string* out) { out->append(reinterpret_cast<const char*>(&v), 4); }
void AppendF32(float v, std::string* out) { out->append(reinterpret_cast<const char*>(&v), 4); }

// A binary STL (little-endian host assumed, as on every machine pectus targets) with `count` in its header.
std::string BinaryStl(const std::string& header, std::uint32_t count,
                      const std::vector<Triangle>& triangles) {
  std::string out = header;
  out.resize(80, '\0');
  AppendU32(count, &out);
  for (const Triangle& t : triangles) {
    for (int k = 0; k < 3; ++k) AppendF32(0.0f, &out);
    for (float v : t) AppendF32(v, &out);
    out.append(2, '\0');
  }
  return out;
}

const std::vector<Triangle> kSquare = {Triangle{0, 0, 0, 1, 0, 0, 1, 1, 0},
                                       Triangle{0, 0, 0, 1, 1, 0, 0, 1, 0}};

TEST(StlIo, BinaryWithSolidHeaderIsReadAsBinaryAndWelded) {
  // Many exporters start the binary header with "solid"; the size decides.
  FileSummary summary;
  const TriangleMesh mesh =
      ParseStl(BinaryStl("solid exported by a CAD program", 2, kSquare), "square.stl", &summary);
  EXPECT_EQ(summary.format, "stl");
  EXPECT_EQ(summary.encoding, "binary");
  ASSERT_EQ(mesh.num_vertices(), 4);  // 6 corners, 2 shared
  ASSERT_EQ(mesh.num_faces(), 2);
  EXPECT_EQ(mesh.faces.row(0), Eigen::RowVector3i(0, 1, 2));
  EXPECT_EQ(mesh.faces.row(1), Eigen::RowVector3i(0, 2, 3));
  EXPECT_EQ(mesh.vertices.positions.row(3), Eigen::RowVector3d(0, 1, 0));
  ASSERT_EQ(summary.comments.size(), 1u);
  EXPECT_EQ(summary.comments[0], "solid exported by a CAD program");
}

TEST(StlIo, AsciiIsParsedAndWelded) {
  const std::string ascii =
      "solid square\n"
      "  facet normal 0 0 1\n    outer loop\n      vertex 0 0 0\n      vertex 1 0 0\n      vertex 1 1 0\n"
      "    endloop\n  endfacet\n"
      "  FACET NORMAL 0 0 1\n    OUTER LOOP\n      VERTEX -0.0 0 0\n      VERTEX 1 1 0\n      VERTEX 0 1 0\n"
      "    ENDLOOP\n  ENDFACET\n"
      "endsolid square\n";
  FileSummary summary;
  const TriangleMesh mesh = ParseStl(ascii, "square.stl", &summary);
  EXPECT_EQ(summary.encoding, "ascii");
  EXPECT_EQ(mesh.num_vertices(), 4);  // -0.0 and 0 are one position
  ASSERT_EQ(mesh.num_faces(), 2);
  EXPECT_EQ(mesh.faces.row(1), Eigen::RowVector3i(0, 2, 3));
}

TEST(StlIo, BinaryRoundTripWithinFloatPrecision) {
  const TriangleMesh sphere = testing::MakeSphere();
  std::ostringstream out;
  WriteStl(out, sphere, WriteOptions{.binary = true, .comment = "unit test"});
  const std::string bytes = out.str();
  ASSERT_EQ(bytes.size(), 84 + 50 * static_cast<std::size_t>(sphere.num_faces()));
  EXPECT_NE(bytes.substr(0, 5), "solid");  // so that first-word readers do not take it for ASCII
  const TriangleMesh back = ParseStl(bytes, "sphere.stl");
  EXPECT_EQ(back.num_vertices(), sphere.num_vertices());
  EXPECT_LT(testing::MaxCornerDistance(sphere, back), 1e-4);  // float storage of ~100 mm coordinates

  // The stored facet normal is the unit normal of the triangle.
  float n[3];
  std::memcpy(n, bytes.data() + 84, 12);
  const Eigen::Vector3d a = sphere.vertices.positions.row(sphere.faces(0, 0));
  const Eigen::Vector3d b = sphere.vertices.positions.row(sphere.faces(0, 1));
  const Eigen::Vector3d c = sphere.vertices.positions.row(sphere.faces(0, 2));
  const Eigen::Vector3d expected = (b - a).cross(c - a).normalized();
  EXPECT_LT((Eigen::Vector3d(n[0], n[1], n[2]) - expected).norm(), 1e-6);
}

TEST(StlIo, AsciiRoundTripIsExact) {
  const TriangleMesh sphere = testing::MakeSphere();
  std::ostringstream out;
  WriteStl(out, sphere, WriteOptions{.binary = false, .comment = ""});
  EXPECT_EQ(out.str().substr(0, 12), "solid pectus");
  FileSummary summary;
  const TriangleMesh back = ParseStl(out.str(), "sphere.stl", &summary);
  EXPECT_EQ(summary.encoding, "ascii");
  EXPECT_EQ(back.num_vertices(), sphere.num_vertices());
  EXPECT_EQ(testing::MaxCornerDistance(sphere, back), 0.0);
}

TEST(StlIo, TruncatedBinaryIsAClearError) {
  std::string bytes = BinaryStl("binary", 2, kSquare);
  bytes.resize(bytes.size() - 50);
  EXPECT_TRUE(ThrowsBadInput(
      [&] { ParseStl(bytes, "cut.stl"); },
      "truncated binary STL: header says 2 triangles (needs 184 bytes) but the file has 134", "cut.stl"));
}

TEST(StlIo, HugeCountInTinyFileIsAnErrorNotAnAllocation) {
  std::string bytes = BinaryStl("binary", 2000000000u, kSquare);
  bytes.resize(1024, '\0');
  const auto start = std::chrono::steady_clock::now();
  EXPECT_TRUE(
      ThrowsBadInput([&] { ParseStl(bytes, "huge.stl"); },
                     "truncated binary STL: header says 2000000000 triangles (needs 100000000084 bytes) but "
                     "the file has 1024",
                     "huge.stl"));
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 0.5);
}

TEST(StlIo, MalformedInputIsAnErrorNamingFileAndLine) {
  EXPECT_TRUE(ThrowsBadInput([] { ParseStl("", "empty.stl"); }, "file is empty", "empty.stl"));
  EXPECT_TRUE(ThrowsBadInput([] { ParseStl("hello", "short.stl"); }, "too short", "short.stl"));
  const std::string head = "solid s\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\n";
  EXPECT_TRUE(ThrowsBadInput([&] { ParseStl(head + "vertex 1 zero 0\n", "num.stl"); },
                             "'zero' is not a number", "num.stl", 5));
  EXPECT_TRUE(
      ThrowsBadInput([&] { ParseStl(head + "vertex 1 nan 0\n", "nan.stl"); }, "non-finite", "nan.stl", 5));
  EXPECT_TRUE(
      ThrowsBadInput([&] { ParseStl(head + "vertex 1 0\n", "two.stl"); }, "3 coordinates", "two.stl", 5));
  EXPECT_TRUE(ThrowsBadInput([&] { ParseStl(head + "vertex 1 0 0\n", "cut.stl"); }, "ends inside a facet",
                             "cut.stl"));
  EXPECT_TRUE(ThrowsBadInput([&] { ParseStl(head + "endloop\n", "few.stl"); }, "1 vertices", "few.stl", 5));
  EXPECT_TRUE(ThrowsBadInput([] { ParseStl("solid s\nvertex 0 0 0\n", "loop.stl"); }, "unexpected 'vertex'",
                             "loop.stl", 2));
  const float nan = std::numeric_limits<float>::quiet_NaN();
  EXPECT_TRUE(ThrowsBadInput(
      [&] {
        ParseStl(BinaryStl("b", 1, {Triangle{0, 0, 0, 1, 0, 0, 0, nan, 0}}), "n.stl");
      },
      "triangle 1 has a non-finite coordinate", "n.stl"));
}

TEST(StlIo, EmptyBinaryHasNoTriangles) {
  const TriangleMesh mesh = ParseStl(BinaryStl("nothing", 0, {}), "none.stl");
  EXPECT_EQ(mesh.num_faces(), 0);
  EXPECT_EQ(mesh.num_vertices(), 0);
}

}  // namespace
}  // namespace pectus
