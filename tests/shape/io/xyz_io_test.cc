#include <gtest/gtest.h>

#include <sstream>

#include "shape/core/error.h"
#include "shape/io/format_parsers.h"
#include "tests/shape/io/io_test_util.h"

namespace pectus {
namespace {

using testing::ThrowsBadInput;

TEST(XyzIo, ColumnCountsWithoutHeader) {
  // 3 columns: positions. Separators may be blanks, tabs, commas or semicolons.
  const TriangleMesh a = ParseXyz("1 2 3\n4\t5\t6\n7,8,9\n10; 11 ;12\n", "a.xyz");
  ASSERT_EQ(a.num_vertices(), 4);
  EXPECT_EQ(a.vertices.positions.row(3), Eigen::RowVector3d(10, 11, 12));
  EXPECT_FALSE(a.vertices.has_normals());
  EXPECT_EQ(a.num_faces(), 0);

  // 6 columns: positions and normals.
  const TriangleMesh b = ParseXyz("# scanner export\n1 2 3 0 0 1\n4 5 6 0.6 0.8 0\n", "b.xyz");
  ASSERT_TRUE(b.vertices.has_normals());
  EXPECT_EQ(b.vertices.normals.row(1), Eigen::RowVector3d(0.6, 0.8, 0));

  // Other counts: positions then scalars named by column.
  const TriangleMesh c = ParseXyz("1 2 3 0.5\n4 5 6 0.25\n", "c.xyz");
  ASSERT_EQ(c.vertices.scalars.count("s3"), 1u);
  EXPECT_EQ(c.vertices.scalars.at("s3"), Eigen::Vector2d(0.5, 0.25));
  const TriangleMesh d = ParseXyz("1 2 3 7 8 9 10\n", "d.xyz");
  EXPECT_FALSE(d.vertices.has_normals());
  EXPECT_EQ(d.vertices.scalars.size(), 4u);
  EXPECT_EQ(d.vertices.scalars.at("s6")[0], 10.0);
}

TEST(XyzIo, HeaderNamesColumnsInAnyOrder) {
  FileSummary summary;
  const TriangleMesh m =
      ParseXyz("\xEF\xBB\xBF\"Z\",x,y,intensity,nz,nx,ny\n3,1,2,0.9,1,0,0\n", "h.csv", &summary);
  ASSERT_EQ(m.num_vertices(), 1);
  EXPECT_EQ(m.vertices.positions.row(0), Eigen::RowVector3d(1, 2, 3));
  EXPECT_EQ(m.vertices.normals.row(0), Eigen::RowVector3d(0, 0, 1));
  EXPECT_EQ(m.vertices.scalars.at("intensity")[0], 0.9);
  EXPECT_EQ(summary.format, "csv");
  ASSERT_EQ(summary.elements.size(), 1u);
  EXPECT_EQ(summary.elements[0].count, 1);
  EXPECT_EQ(summary.elements[0].properties.size(), 7u);
}

TEST(XyzIo, XyzRoundTripIsExact) {
  const TriangleMesh sphere = testing::MakeSphere();
  std::ostringstream out;
  WriteXyz(out, sphere, ' ', WriteOptions{.binary = true, .comment = "sphere"});
  EXPECT_EQ(out.str().substr(0, 9), "# sphere\n");
  const TriangleMesh back = ParseXyz(out.str(), "sphere.xyz");
  EXPECT_EQ(back.vertices.positions, sphere.vertices.positions);
  EXPECT_EQ(back.vertices.normals, sphere.vertices.normals);
  EXPECT_TRUE(back.vertices.scalars.empty());  // no header, so no names: scalars are not written
  EXPECT_EQ(back.num_faces(), 0);
}

TEST(XyzIo, CsvRoundTripKeepsScalarsExactly) {
  TriangleMesh sphere = testing::MakeSphere();
  sphere.vertices.scalars["confidence"] = Eigen::VectorXd::LinSpaced(sphere.num_vertices(), 0.0, 1.0);
  std::ostringstream out;
  WriteXyz(out, sphere, ',', {});
  EXPECT_EQ(out.str().substr(0, out.str().find('\n')), "x,y,z,nx,ny,nz,confidence,height");
  const TriangleMesh back = ParseXyz(out.str(), "sphere.csv");
  EXPECT_EQ(back.vertices.positions, sphere.vertices.positions);
  EXPECT_EQ(back.vertices.normals, sphere.vertices.normals);
  ASSERT_EQ(back.vertices.scalars.size(), 2u);
  EXPECT_EQ(back.vertices.scalars.at("confidence"), sphere.vertices.scalars.at("confidence"));
  EXPECT_EQ(back.vertices.scalars.at("height"), sphere.vertices.scalars.at("height"));
}

TEST(XyzIo, ScalarsMayBeNaNButCoordinatesMayNot) {
  const TriangleMesh m = ParseXyz("x y z distance\n1 2 3 nan\n", "d.xyz");
  EXPECT_TRUE(std::isnan(m.vertices.scalars.at("distance")[0]));
  EXPECT_TRUE(
      ThrowsBadInput([] { ParseXyz("1 2 3\n4 nan 6\n", "nan.xyz"); }, "non-finite coordinate", "nan.xyz", 2));
  EXPECT_TRUE(ThrowsBadInput([] { ParseXyz("1 2 3 0 0 1\n4 5 6 0 inf 1\n", "inf.xyz"); }, "non-finite",
                             "inf.xyz", 2));
}

TEST(XyzIo, MalformedInputIsAnErrorNamingFileAndLine) {
  EXPECT_TRUE(ThrowsBadInput([] { ParseXyz("1 2 3\n\n4 5 6 7\n", "cols.xyz"); },
                             "this line has 4 columns but the file's first line has 3", "cols.xyz", 3));
  EXPECT_TRUE(ThrowsBadInput([] { ParseXyz("1 2\n", "two.xyz"); }, "at least 3 columns", "two.xyz", 1));
  EXPECT_TRUE(ThrowsBadInput([] { ParseXyz("1 2 3\n4 five 6\n", "word.xyz"); }, "'five' is not a number",
                             "word.xyz", 2));
  EXPECT_TRUE(ThrowsBadInput([] { ParseXyz("1,,3\n", "gap.csv"); }, "column 2 is empty", "gap.csv", 1));
  EXPECT_TRUE(ThrowsBadInput([] { ParseXyz("a,b,c\n1,2,3\n", "hdr.csv"); }, "x, y and z", "hdr.csv", 1));
  EXPECT_TRUE(ThrowsBadInput([] { ParseXyz("x,y,z,x\n", "dup.csv"); }, "appears twice", "dup.csv", 1));
  EXPECT_TRUE(
      ThrowsBadInput([] { ParseXyz("x,y,z,nx\n", "nrm.csv"); }, "not all of the normal", "nrm.csv", 1));
  EXPECT_TRUE(ThrowsBadInput([] { ParseXyz("# nothing\n\n", "none.xyz"); }, "no points", "none.xyz"));
}

}  // namespace
}  // namespace pectus
