// The PCD reader on files written by hand, byte by byte, in all three encodings: known values read back
// exactly, and every malformed header or data an error naming the file (and the line). Built without PCL
// (the core-only sanitizer build runs it); pcd_io_peer_test.cc compares with PCL's own writer and reader.
#include <gtest/gtest.h>
#include <lzf.h>

#include <cstring>
#include <limits>

#include "shape/core/error.h"
#include "shape/core/log.h"
#include "shape/io/format_parsers.h"
#include "shape/io/mesh_io.h"
#include "tests/shape/io/io_test_util.h"

namespace pectus {
namespace {

using testing::ThrowsBadInput;

TriangleMesh ReadPcd(const std::filesystem::path& path, FileSummary* summary = nullptr) {
  return ReadMesh(path, ReadOptions{.warn_units = false}, summary);
}

template <typename T>
void Append(std::string* out, T value) {
  out->append(reinterpret_cast<const char*>(&value), sizeof value);
}

// binary_compressed data: the two sizes, then the LZF block of `raw`.
std::string Compressed(const std::string& raw) {
  std::string block(raw.size() + 64, '\0');
  const unsigned size = lzf_compress(raw.data(), static_cast<unsigned>(raw.size()), block.data(),
                                     static_cast<unsigned>(block.size()));
  EXPECT_GT(size, 0u);
  std::string out;
  Append<std::uint32_t>(&out, size);
  Append<std::uint32_t>(&out, static_cast<std::uint32_t>(raw.size()));
  return out + block.substr(0, size);
}

// Three points with x y z, a normal, a packed colour and a 16-bit intensity.
struct KnownPoint {
  float x, y, z, nx, ny, nz;
  std::uint32_t rgb;
  std::uint16_t intensity;
};
constexpr KnownPoint kPoints[] = {{1.5f, -2.25f, 1000.0f, 0, 0, 1, 0xFF102030u, 7},
                                  {0.1f, 0.0f, -3e5f, 1, 0, 0, 0x00FFFFFFu, 65535},
                                  {3.0f, 4.0f, 5.0f, 0, 1, 0, 0, 0}};
constexpr char kKnownHeader[] =
    "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\n"
    "FIELDS x y z normal_x normal_y normal_z rgb intensity\nSIZE 4 4 4 4 4 4 4 2\n"
    "TYPE F F F F F F F U\nCOUNT 1 1 1 1 1 1 1 1\nWIDTH 3\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 3\n";

std::string KnownAscii() {
  return std::string(kKnownHeader) +
         "DATA ascii\n1.5 -2.25 1000 0 0 1 4279246896 7\n0.1 0 -3e+05 1 0 0 16777215 65535\n\n"
         "3 4 5 0 1 0 0 0\n";
}

std::string KnownBinary() {
  std::string data;
  for (const KnownPoint& p : kPoints) {
    for (float v : {p.x, p.y, p.z, p.nx, p.ny, p.nz}) Append(&data, v);
    Append(&data, p.rgb);
    Append(&data, p.intensity);
  }
  return std::string(kKnownHeader) + "DATA binary\n" + data;
}

std::string KnownCompressed() {
  std::string raw;  // field after field
  for (float KnownPoint::*f :
       {&KnownPoint::x, &KnownPoint::y, &KnownPoint::z, &KnownPoint::nx, &KnownPoint::ny, &KnownPoint::nz}) {
    for (const KnownPoint& p : kPoints) Append(&raw, p.*f);
  }
  for (const KnownPoint& p : kPoints) Append(&raw, p.rgb);
  for (const KnownPoint& p : kPoints) Append(&raw, p.intensity);
  return std::string(kKnownHeader) + "DATA binary_compressed\n" + Compressed(raw);
}

TEST(PcdIo, ReadsKnownPointsInEveryEncoding) {
  const testing::TempDir dir;
  for (const auto& [file, bytes, encoding] :
       {std::tuple{"ascii.pcd", KnownAscii(), "ascii"}, std::tuple{"binary.pcd", KnownBinary(), "binary"},
        std::tuple{"compressed.pcd", KnownCompressed(), "binary_compressed"}}) {
    SCOPED_TRACE(file);
    FileSummary summary;
    const TriangleMesh mesh = ReadPcd(dir.Write(file, bytes), &summary);
    const PointCloud& v = mesh.vertices;
    ASSERT_EQ(v.size(), 3);
    ASSERT_TRUE(v.has_normals());
    ASSERT_TRUE(v.has_colors());
    ASSERT_EQ(v.scalars.size(), 1u);
    for (int i = 0; i < 3; ++i) {
      const KnownPoint& p = kPoints[i];
      // Floats widened to double: exact in every encoding (the ascii text is the float's shortest form).
      EXPECT_EQ(v.positions.row(i), Eigen::RowVector3d(p.x, p.y, p.z));
      EXPECT_EQ(v.normals.row(i), Eigen::RowVector3d(p.nx, p.ny, p.nz));
      const Eigen::RowVector3i rgb((p.rgb >> 16) & 0xFF, (p.rgb >> 8) & 0xFF, p.rgb & 0xFF);
      EXPECT_EQ(v.colors.row(i).cast<int>(), rgb);
      EXPECT_EQ(v.scalars.at("intensity")[i], p.intensity);
    }
    EXPECT_EQ(summary.format, "pcd");
    EXPECT_EQ(summary.encoding, encoding);
    ASSERT_EQ(summary.elements.size(), 1u);
    EXPECT_EQ(summary.elements[0].count, 3);
    EXPECT_EQ(summary.elements[0].properties.front(), "float x");
    EXPECT_EQ(summary.elements[0].properties.back(), "ushort intensity");
    EXPECT_EQ(summary.comments, std::vector<std::string>{"PCD version 0.7, width 3, height 1"});
  }
}

TEST(PcdIo, ReadsOldVersionsPaddingAndDescriptors) {
  const testing::TempDir dir;
  // PCD 0.5: COLUMNS, no SIZE, TYPE or COUNT (4-byte floats), CRLF line ends.
  FileSummary summary;
  const TriangleMesh old = ReadPcd(
      dir.Write("old.pcd", "VERSION .5\r\nCOLUMNS x y z\r\nPOINTS 2\r\nDATA ascii\r\n1 2 3\r\n4 5 6\r\n"),
      &summary);
  ASSERT_EQ(old.num_vertices(), 2);
  EXPECT_EQ(old.vertices.positions.row(1), Eigen::RowVector3d(4, 5, 6));
  EXPECT_EQ(summary.comments, std::vector<std::string>{"PCD version 0.5, width 2, height 1"});

  // Binary as PCL writes a PointXYZ (x y z and 4 bytes of padding), with a 3-element descriptor and a
  // double: neither the padding nor the descriptor becomes a scalar.
  const std::string header =
      "FIELDS x y z _ fpfh weight\nSIZE 4 4 4 1 2 8\nTYPE F F F U I F\nCOUNT 1 1 1 4 3 1\nWIDTH 2\n";
  std::string binary;
  for (int i = 0; i < 2; ++i) {
    for (float v : {1.0f + i, 2.0f, 3.0f}) Append(&binary, v);
    binary.append(4, '\x7f');
    for (int d : {-1, 2, 3}) Append(&binary, static_cast<std::int16_t>(d));
    Append(&binary, 0.5 + i);
  }
  const TriangleMesh padded = ReadPcd(dir.Write("padded.pcd", header + "DATA binary\n" + binary));
  ASSERT_EQ(padded.num_vertices(), 2);
  EXPECT_EQ(padded.vertices.positions.row(1), Eigen::RowVector3d(2, 2, 3));
  ASSERT_EQ(padded.vertices.scalars.size(), 1u);
  EXPECT_EQ(padded.vertices.scalars.at("weight")[1], 1.5);

  // binary_compressed leaves the padding out of its block.
  std::string raw;
  for (float v : {1.0f, 2.0f, 2.0f, 2.0f, 3.0f, 3.0f}) Append(&raw, v);
  for (int d : {-1, 2, 3, -1, 2, 3}) Append(&raw, static_cast<std::int16_t>(d));
  for (double w : {0.5, 1.5}) Append(&raw, w);
  const TriangleMesh compressed =
      ReadPcd(dir.Write("padded_c.pcd", header + "DATA binary_compressed\n" + Compressed(raw)));
  EXPECT_EQ(compressed.vertices.positions, padded.vertices.positions);
  EXPECT_EQ(compressed.vertices.scalars.at("weight"), padded.vertices.scalars.at("weight"));
}

TEST(PcdIo, AsciiNaNsOfAnOrganizedCloudAreLeftOut) {
  const testing::TempDir dir;
  const std::string path = dir.Write("organized.pcd",
                                     "FIELDS x y z\nSIZE 4 4 8\nTYPE F F F\nWIDTH 2\nHEIGHT 2\nDATA ascii\n"
                                     "0 0 1\nnan nan nan\n2 0 1\n3 nan 1\n")
                               .string();
  const bool quiet = IsQuiet();
  SetQuiet(true);
  const WarningCollector collector;
  const TriangleMesh mesh = ReadPcd(path);
  SetQuiet(quiet);
  ASSERT_EQ(mesh.num_vertices(), 2);
  EXPECT_EQ(mesh.vertices.positions.col(0), Eigen::Vector2d(0, 2));
  ASSERT_EQ(collector.warnings().size(), 1u);
  EXPECT_NE(collector.warnings()[0].find("2 of 4 points"), std::string::npos) << collector.warnings()[0];
}

TEST(PcdIo, AnEmptyCloudIsNoError) {
  // As PCL's reader returned it: no points, in any encoding (binary_compressed without its sizes).
  const testing::TempDir dir;
  for (const char* encoding : {"ascii", "binary", "binary_compressed"}) {
    SCOPED_TRACE(encoding);
    FileSummary summary;
    const TriangleMesh mesh = ReadPcd(
        dir.Write("empty_cloud.pcd",
                  std::string("VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 0\n"
                              "HEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 0\nDATA ") +
                      encoding + "\n"),
        &summary);
    EXPECT_EQ(mesh.num_vertices(), 0);
    EXPECT_EQ(summary.elements.at(0).count, 0);
  }
}

TEST(PcdIo, MalformedFilesAreErrorsNamingTheFile) {
  const testing::TempDir dir;
  EXPECT_TRUE(ThrowsBadInput([&] { ReadPcd(dir / "missing.pcd"); }, "no such file", "missing.pcd"));
  EXPECT_TRUE(ThrowsBadInput([&] { ReadPcd(dir.Write("empty.pcd", "")); }, "file is empty", "empty.pcd"));
  EXPECT_TRUE(ThrowsBadInput([&] { ReadPcd(dir.Write("junk.pcd", "this is not a point cloud\n")); }, "PCD",
                             "junk.pcd"));
  const std::filesystem::path no_xyz =
      dir.Write("noxyz.pcd",
                "VERSION 0.7\nFIELDS normal_x normal_y normal_z curvature\nSIZE 4 4 4 4\nTYPE F F F F\n"
                "COUNT 1 1 1 1\nWIDTH 1\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 1\nDATA ascii\n0 0 1 0\n");
  EXPECT_TRUE(ThrowsBadInput([&] { ReadPcd(no_xyz); }, "no x, y, z fields", "noxyz.pcd"));

  // A binary file cut short.
  const std::string whole = KnownBinary();
  const std::filesystem::path cut = dir.Write("cut.pcd", whole.substr(0, whole.size() - 20));
  EXPECT_TRUE(ThrowsBadInput([&] { ReadPcd(cut); }, "PCD", "cut.pcd"));

  // Found by fuzzing: PCL's reader dereferenced a null pointer on this header (a keyword PCL does not
  // know, as it matches keywords in capitals only).
  const std::filesystem::path odd =
      dir.Write("odd.pcd", "VErSION\nFIELDS z\nSIZE 4\nPOINTS 2\nDATA ascii\n 00");
  EXPECT_TRUE(ThrowsBadInput([&] { ReadPcd(odd); }, "unexpected 'VErSION' in the header", "odd.pcd", 1));
}

struct BadFile {
  const char* what;
  std::string bytes;
  const char* phrase;
  std::int64_t line;  // 0: no line
};

TEST(PcdIo, MalformedHeadersAreErrorsNamingTheFileAndLine) {
  const std::string xyz = "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\n";
  const std::string data = "DATA ascii\n1 2 3\n";
  const BadFile cases[] = {
      {"points not width x height", xyz + "WIDTH 4\nHEIGHT 2\nPOINTS 7\n" + data,
       "POINTS 7 is not WIDTH x HEIGHT", 0},
      {"keyword in odd capitals", "FIELDS x y z\nSize 4 4 4\n" + data, "unexpected 'Size' in the header", 2},
      {"lower-case keyword", "fields x y z\n" + data, "unexpected 'fields'", 1},
      {"DATA in capitals", xyz + "POINTS 1\nDATA ASCII\n", "unknown DATA 'ASCII'", 5},
      {"no DATA", xyz + "POINTS 1\n", "no DATA line", 0},
      {"no FIELDS", "SIZE 4\nPOINTS 1\n" + data, "has no FIELDS", 0},
      {"FIELDS twice", xyz + "COLUMNS x y z\nPOINTS 1\n" + data, "COLUMNS is given twice", 4},
      {"size 3", "FIELDS x y z\nSIZE 4 3 4\n" + data, "field size '3' is not 1, 2, 4 or 8", 2},
      {"float of 2 bytes", "FIELDS x y z\nSIZE 4 2 4\nTYPE F F F\nPOINTS 1\n" + data,
       "field 'y' has TYPE F and SIZE 2 (a float is 4 or 8 bytes)", 1},
      // Found by fuzzing (valgrind on the corpus): with no TYPE line PCL's reader took every field for a
      // 4-byte float and wrote past its buffer where SIZE said 1 byte.
      {"sizes of 1 without TYPE",
       "VERSION .7\nFIELDS x y z a b c\nSIZE 1 1 1 1 1 1\nWIDTH 2\nHEIGHT 1\nPOINTS 2\n"
       "DATA ascii\n0 0 0 0 0 1\n1 2 3 0 1 0\n",
       "field 'x' has TYPE F and SIZE 1", 2},
      {"type letter", "FIELDS x y z\nSIZE 4 4 4\nTYPE F f F\nPOINTS 1\n" + data,
       "field type 'f' is not I, U or F", 3},
      {"sizes for fields", "FIELDS x y z\nSIZE 4 4\nPOINTS 1\n" + data, "SIZE gives 2 values for 3 fields",
       1},
      {"counts for fields", xyz + "COUNT 1 1 1 1\nPOINTS 1\n" + data, "COUNT gives 4 values for 3 fields", 1},
      {"count 0", xyz + "COUNT 1 0 1\nPOINTS 1\n" + data, "field count '0' is not between 1", 4},
      {"absurd count", xyz + "COUNT 1 1 4294967296\nPOINTS 1\n" + data, "field count '4294967296'", 4},
      {"absurd width", xyz + "WIDTH 99999999999999999999\n" + data, "is not a valid count", 4},
      {"negative height", xyz + "WIDTH 1\nHEIGHT -1\n" + data, "'-1' is not a valid count", 5},
      {"width x height overflows", xyz + "WIDTH 1099511627776\nHEIGHT 1099511627776\n" + data,
       "too many points", 0},
      {"two widths", xyz + "WIDTH 1 1\n" + data, "WIDTH needs one number", 4},
      {"height without width", xyz + "HEIGHT 1\nPOINTS 1\n" + data, "HEIGHT but no WIDTH", 0},
      {"no count of points", xyz + data, "neither WIDTH nor POINTS", 0},
      {"version 0.8", "VERSION 0.8\n" + xyz + "POINTS 1\n" + data, "VERSION '0.8' is not 0.5, 0.6 or 0.7", 1},
      {"short viewpoint", xyz + "VIEWPOINT 0 0 0\nPOINTS 1\n" + data, "VIEWPOINT needs 7 numbers", 4},
  };
  const testing::TempDir dir;
  for (const BadFile& c : cases) {
    SCOPED_TRACE(c.what);
    EXPECT_TRUE(ThrowsBadInput([&] { ReadPcd(dir.Write("bad.pcd", c.bytes)); }, c.phrase, "bad.pcd", c.line));
  }
}

// Found by fuzzing (valgrind on the corpus): PCL's reader went on reading header keywords after the DATA
// line, so that data starting with "SIZE 8 4 4" changed the layout after the size checks (a read past the
// buffer). The data starts after the DATA line, whatever it looks like.
TEST(PcdIo, DataAfterTheDataLineIsDataWhateverItLooksLike) {
  const std::string data = "SIZE 8 4 4\n\n";  // 12 bytes: one point of three floats
  const testing::TempDir dir;
  const TriangleMesh mesh =
      ReadPcd(dir.Write("data.pcd", "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH 1\nDATA binary\n" + data));
  ASSERT_EQ(mesh.num_vertices(), 1);
  float xyz[3];
  std::memcpy(xyz, data.data(), sizeof xyz);
  EXPECT_EQ(mesh.vertices.positions.row(0), Eigen::RowVector3d(xyz[0], xyz[1], xyz[2]));
}

TEST(PcdIo, MalformedDataIsAnErrorNamingTheFile) {
  const std::string xyz = "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\n";
  const std::string rgb = "FIELDS x y z rgb\nSIZE 4 4 4 1\nTYPE F F F U\nCOUNT 1 1 1 3\n";
  std::string raw;  // two points of x y z, field after field
  for (float v : {1.0f, 2.0f, 3.0f, 4.0f, 5.0f, 6.0f}) Append(&raw, v);
  const std::string block = Compressed(raw);
  const auto with_sizes = [&](std::uint32_t compressed, std::uint32_t uncompressed, const std::string& rest) {
    std::string out;
    Append(&out, compressed);
    Append(&out, uncompressed);
    return out + rest;
  };
  const std::string compressed = xyz + "WIDTH 2\nDATA binary_compressed\n";
  std::string corrupt = block;
  corrupt[8] = '\x1f';  // a literal run longer than the block
  const BadFile cases[] = {
      {"binary cut short", xyz + "WIDTH 2\nDATA binary\n" + raw.substr(0, 20), "truncated PCD file", 0},
      {"ascii points missing", xyz + "WIDTH 3\nDATA ascii\n1.000 2.000 3.000\n4.000 5.000 6.000\n\n",
       "declares 3 points but the data holds 2", 0},
      {"ascii absurd point count", xyz + "WIDTH 1000000000000\nDATA ascii\n1 2 3\n", "truncated PCD file", 0},
      {"ascii word", xyz + "WIDTH 2\nDATA ascii\n1 2 3\n4 five 6\n", "'five' is not a float", 7},
      {"ascii values missing", xyz + "WIDTH 2\nDATA ascii\n1 2 3\n4 5\n", "has 2 values; its fields need 3",
       7},
      {"ascii values left over", xyz + "WIDTH 1\nDATA ascii\n1 2 3 4\n", "more than the 3 values", 6},
      {"ascii byte out of range", rgb + "WIDTH 1\nDATA ascii\n1 2 3 4 300 6\n", "'300' is not a uchar", 7},
      {"no compressed sizes", compressed + "abc", "a compressed block", 0},
      {"compressed size beyond the file", compressed + with_sizes(1000, 24, block.substr(8)),
       "1000 compressed bytes", 0},
      {"uncompressed size not the layout",
       compressed + with_sizes(static_cast<std::uint32_t>(block.size() - 8), 28, block.substr(8)),
       "compressed block holds 28 bytes but the header's 2 points need 24", 0},
      {"uncompressed size beyond LZF",
       xyz + "WIDTH 100000000\nDATA binary_compressed\n" + with_sizes(4, 1200000000, "abcd"),
       "cannot expand to 1200000000", 0},
      {"corrupt LZF block", compressed + corrupt, "compressed block is corrupt", 0},
  };
  const testing::TempDir dir;
  for (const BadFile& c : cases) {
    SCOPED_TRACE(c.what);
    EXPECT_TRUE(ThrowsBadInput([&] { ReadPcd(dir.Write("bad.pcd", c.bytes)); }, c.phrase, "bad.pcd", c.line));
  }
}

}  // namespace
}  // namespace pectus
