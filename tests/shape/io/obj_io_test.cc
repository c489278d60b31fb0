#include <gtest/gtest.h>

#include <array>
#include <sstream>

#include "shape/core/error.h"
#include "shape/io/format_parsers.h"
#include "tests/shape/io/io_test_util.h"

namespace pectus {
namespace {

using testing::ThrowsBadInput;

Faces3 FacesOf(std::initializer_list<std::array<int, 3>> rows) {
  Faces3 f(static_cast<Eigen::Index>(rows.size()), 3);
  Eigen::Index i = 0;
  for (const auto& r : rows) f.row(i++) << r[0], r[1], r[2];
  return f;
}

TEST(ObjIo, EveryFaceFormAndPolygonFan) {
  const std::string obj =
      "# a square pyramid\n"
      "mtllib pyramid.mtl\n"
      "o pyramid\n"
      "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0.5 0.5 1 1.0\n"
      "vt 0 0\nvt 1 0\nvt 1 1\n"
      "vn 0 0 -1\n"
      "g base\nusemtl stone\ns off\n"
      "f 1//1 4//1 3//1 2//1\n"  // quad: fanned into two triangles
      "f 1 2 5\n"
      "f 2/2 3/3 5/1\n"
      "f -3/1/1 -2/2/1 -1/3/1\n"  // relative: vertices 3 4 5
      "f 4 1 5\n";
  FileSummary summary;
  const TriangleMesh mesh = ParseObj(obj, "pyramid.obj", &summary);
  ASSERT_EQ(mesh.num_vertices(), 5);
  EXPECT_EQ(mesh.vertices.positions.row(4), Eigen::RowVector3d(0.5, 0.5, 1.0));
  EXPECT_EQ(mesh.faces, FacesOf({{0, 3, 2}, {0, 2, 1}, {0, 1, 4}, {1, 2, 4}, {2, 3, 4}, {3, 0, 4}}));
  // Only some corners carry normals: no vertex normals.
  EXPECT_FALSE(mesh.vertices.has_normals());
  EXPECT_FALSE(mesh.vertices.has_colors());
  EXPECT_EQ(summary.format, "obj");
  EXPECT_EQ(summary.encoding, "ascii");
  ASSERT_EQ(summary.elements.size(), 4u);  // vertex, normal, texcoord, face
  EXPECT_EQ(summary.elements[0].count, 5);
  EXPECT_EQ(summary.elements.back().name, "face");
  EXPECT_EQ(summary.elements.back().count, 5);  // polygons as in the file
  ASSERT_EQ(summary.comments.size(), 1u);
  EXPECT_EQ(summary.comments[0], "a square pyramid");
}

TEST(ObjIo, PentagonFansFromTheFirstCorner) {
  const TriangleMesh mesh = ParseObj("v 0 0 0\nv 2 0 0\nv 3 1 0\nv 1 2 0\nv -1 1 0\nf 1 2 3 4 5\n", "p.obj");
  EXPECT_EQ(mesh.faces, FacesOf({{0, 1, 2}, {0, 2, 3}, {0, 3, 4}}));
}

TEST(ObjIo, ConsistentCornerNormalsBecomeVertexNormals) {
  // Duplicate vn lines with equal values count as one normal.
  const std::string obj =
      "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\n"
      "vn 0 0 1\nvn 0 0 1\nvn 0.6 0 0.8\nvn 0 0.6 0.8\n"
      "f 1//1 2//3 3//4\nf 2//3 4//2 3//4\n";
  const TriangleMesh mesh = ParseObj(obj, "n.obj");
  ASSERT_TRUE(mesh.vertices.has_normals());
  EXPECT_EQ(mesh.vertices.normals.row(0), Eigen::RowVector3d(0, 0, 1));
  EXPECT_EQ(mesh.vertices.normals.row(1), Eigen::RowVector3d(0.6, 0, 0.8));
  EXPECT_EQ(mesh.vertices.normals.row(2), Eigen::RowVector3d(0, 0.6, 0.8));
  EXPECT_EQ(mesh.vertices.normals.row(3), Eigen::RowVector3d(0, 0, 1));

  // Flat shading: vertex 2 gets two different normals, so normals are dropped.
  const std::string flat =
      "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 1\nvn 0 0 1\nvn 0 -0.7071 0.7071\n"
      "f 1//1 2//1 3//1\nf 2//2 4//2 3//2\n";
  EXPECT_FALSE(ParseObj(flat, "flat.obj").vertices.has_normals());
}

TEST(ObjIo, VertexColourExtension) {
  const TriangleMesh mesh = ParseObj("v 0 0 0 1 0 0\nv 1 0 0 0 0.5 0\nv 0 1 0 0 0 1\nf 1 2 3\n", "c.obj");
  ASSERT_TRUE(mesh.vertices.has_colors());
  EXPECT_EQ(mesh.vertices.colors.row(0).cast<int>(), Eigen::RowVector3i(255, 0, 0));
  EXPECT_EQ(mesh.vertices.colors.row(1).cast<int>(), Eigen::RowVector3i(0, 128, 0));
  EXPECT_EQ(mesh.vertices.colors.row(2).cast<int>(), Eigen::RowVector3i(0, 0, 255));
  // Colours on only some vertices are dropped.
  EXPECT_FALSE(ParseObj("v 0 0 0 1 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "c.obj").vertices.has_colors());
}

TEST(ObjIo, FacesMayReferToVerticesDefinedLater) {
  const TriangleMesh mesh = ParseObj("f 1 2 3\nv 0 0 0\nv 1 0 0\nv 0 1 0\n", "late.obj");
  EXPECT_EQ(mesh.faces, FacesOf({{0, 1, 2}}));
}

TEST(ObjIo, WindowsLineEndingsAndBlankLines) {
  const TriangleMesh mesh = ParseObj("v 0 0 0\r\n\r\nv 1 0 0\r\n  v 0 1 0\r\nf 1 2 3\r\n", "crlf.obj");
  EXPECT_EQ(mesh.num_vertices(), 3);
  EXPECT_EQ(mesh.num_faces(), 1);
}

TEST(ObjIo, RoundTripKeepsPositionsNormalsColoursAndFacesExactly) {
  const TriangleMesh sphere = testing::MakeSphere();
  std::ostringstream out;
  WriteObj(out, sphere, WriteOptions{.binary = true, .comment = "unit test\nsecond line"});
  FileSummary summary;
  const TriangleMesh back = ParseObj(out.str(), "sphere.obj", &summary);
  EXPECT_EQ(back.vertices.positions, sphere.vertices.positions);  // shortest round-trip text: exact
  EXPECT_EQ(back.vertices.normals, sphere.vertices.normals);
  EXPECT_EQ(back.vertices.colors, sphere.vertices.colors);
  EXPECT_EQ(back.faces, sphere.faces);
  EXPECT_TRUE(back.vertices.scalars.empty());  // OBJ has no place for scalars
  ASSERT_GE(summary.comments.size(), 3u);
  EXPECT_EQ(summary.comments[1], "unit test");
  EXPECT_EQ(summary.comments[2], "second line");
}

TEST(ObjIo, PointCloudWithNormalsRoundTrips) {
  TriangleMesh cloud;
  cloud.vertices.positions.resize(2, 3);
  cloud.vertices.positions << 1.25, -2.5, 1e6, 0.1, 0.2, 0.3;
  cloud.vertices.normals.resize(2, 3);
  cloud.vertices.normals << 0, 0, 1, 0.6, 0.8, 0;
  cloud.faces.resize(0, 3);
  std::ostringstream out;
  WriteObj(out, cloud, {});
  const TriangleMesh back = ParseObj(out.str(), "cloud.obj");
  EXPECT_EQ(back.vertices.positions, cloud.vertices.positions);
  EXPECT_EQ(back.vertices.normals, cloud.vertices.normals);
  EXPECT_EQ(back.num_faces(), 0);
}

TEST(ObjIo, MalformedInputIsAnErrorNamingFileAndLine) {
  const std::string three = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
  EXPECT_TRUE(
      ThrowsBadInput([&] { ParseObj(three + "f 1 2 4\n", "range.obj"); }, "out of range", "range.obj", 4));
  EXPECT_TRUE(ThrowsBadInput([&] { ParseObj(three + "f 1 2 0\n", "zero.obj"); }, "index 0", "zero.obj", 4));
  EXPECT_TRUE(
      ThrowsBadInput([&] { ParseObj(three + "f -1 -2 -4\n", "rel.obj"); }, "out of range", "rel.obj", 4));
  EXPECT_TRUE(ThrowsBadInput([&] { ParseObj(three + "f 1//2 2//1 3//1\nvn 0 0 1\n", "vn.obj"); },
                             "out of range", "vn.obj", 4));
  EXPECT_TRUE(ThrowsBadInput([&] { ParseObj(three + "f 1 2\n", "two.obj"); }, "at least 3", "two.obj", 4));
  EXPECT_TRUE(ThrowsBadInput([&] { ParseObj("v 0 0 0\nv 1 x 0\n", "num.obj"); }, "'x' is not a number",
                             "num.obj", 2));
  EXPECT_TRUE(ThrowsBadInput([&] { ParseObj("v 0 0 nan\n", "nan.obj"); }, "non-finite", "nan.obj", 1));
  EXPECT_TRUE(ThrowsBadInput([&] { ParseObj("v 0 inf 0\n", "inf.obj"); }, "non-finite", "inf.obj", 1));
  EXPECT_TRUE(ThrowsBadInput([&] { ParseObj("v 0 0\n", "short.obj"); }, "got 2 numbers", "short.obj", 1));
  EXPECT_TRUE(
      ThrowsBadInput([&] { ParseObj(three + "f 1 2 x\n", "idx.obj"); }, "not a vertex index", "idx.obj", 4));
  EXPECT_TRUE(
      ThrowsBadInput([&] { ParseObj("# only a comment\n", "empty.obj"); }, "no vertices", "empty.obj"));
  EXPECT_TRUE(ThrowsBadInput([&] { ParseObj(std::string("v 0 0 0\n\x01\x02\x03 9\n"), "bin.obj"); },
                             "not an OBJ keyword", "bin.obj", 2));
}

}  // namespace
}  // namespace pectus
