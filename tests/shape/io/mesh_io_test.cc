#include "shape/io/mesh_io.h"

#include <gtest/gtest.h>

#include <functional>

#include "shape/core/error.h"
#include "shape/core/log.h"
#include "tests/shape/io/io_test_util.h"

namespace pectus {
namespace {

using testing::ThrowsBadInput;

ErrorKind KindOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.kind();
  }
  return ErrorKind::kFailure;  // no error at all: the callers expect kUsage or kBadInput
}

TEST(MeshIo, FormatFromExtension) {
  EXPECT_EQ(FormatFromPath("a/b/scan.ply"), FileFormat::kPly);
  EXPECT_EQ(FormatFromPath("SCAN.PLY"), FileFormat::kPly);
  EXPECT_EQ(FormatFromPath("m.obj"), FileFormat::kObj);
  EXPECT_EQ(FormatFromPath("m.Stl"), FileFormat::kStl);
  EXPECT_EQ(FormatFromPath("c.pcd"), FileFormat::kPcd);
  EXPECT_EQ(FormatFromPath("c.xyz"), FileFormat::kXyz);
  EXPECT_EQ(FormatFromPath("c.txt"), FileFormat::kXyz);
  EXPECT_EQ(FormatFromPath("c.pts"), FileFormat::kXyz);
  EXPECT_EQ(FormatFromPath("c.csv"), FileFormat::kCsv);
  EXPECT_EQ(KindOf([] { FormatFromPath("scan.vtk"); }), ErrorKind::kUsage);
  EXPECT_EQ(KindOf([] { FormatFromPath("noextension"); }), ErrorKind::kUsage);
  EXPECT_EQ(ToString(FileFormat::kStl), "stl");
}

struct RoundTripCase {
  std::string file;
  bool binary;
  std::string format;         // FileSummary::format read back
  std::string encoding;       // FileSummary::encoding read back
  double position_tolerance;  // mm
  bool faces, normals, colors, scalars;
};

TEST(MeshIo, OneMeshThroughEveryWrittenFormat) {
  const TriangleMesh sphere = testing::MakeSphere();
  const testing::TempDir dir;
  const std::vector<RoundTripCase> cases = {
      // PLY stores float: ~100 mm coordinates keep about 1e-5 mm.
      {"binary.ply", true, "ply", "binary_little_endian", 1e-4, true, true, true, true},
      {"ascii.ply", false, "ply", "ascii", 1e-4, true, true, true, true},
      // OBJ, ASCII STL, XYZ and CSV write the shortest text that reads back exactly.
      {"mesh.obj", true, "obj", "ascii", 0.0, true, true, true, false},
      {"binary.stl", true, "stl", "binary", 1e-4, true, false, false, false},
      {"ascii.stl", false, "stl", "ascii", 0.0, true, false, false, false},
      {"points.xyz", true, "xyz", "ascii", 0.0, false, true, false, false},
      {"points.csv", true, "csv", "ascii", 0.0, false, true, false, true},
  };
  for (const RoundTripCase& c : cases) {
    SCOPED_TRACE(c.file);
    WriteMesh(dir / c.file, sphere, WriteOptions{.binary = c.binary, .comment = "round trip"});
    FileSummary summary;
    const TriangleMesh back = ReadMesh(dir / c.file, ReadOptions{}, &summary);
    EXPECT_EQ(summary.format, c.format);
    EXPECT_EQ(summary.encoding, c.encoding);
    ASSERT_EQ(back.num_vertices(), sphere.num_vertices());
    if (c.faces) {
      // STL renumbers vertices (welding in order of appearance): compare triangle corners.
      EXPECT_LE(testing::MaxCornerDistance(sphere, back), c.position_tolerance);
    } else {
      EXPECT_EQ(back.num_faces(), 0);
    }
    if (c.format != "stl") {
      EXPECT_LE((back.vertices.positions - sphere.vertices.positions).cwiseAbs().maxCoeff(),
                c.position_tolerance);
    }
    if (c.faces && c.format != "stl") {
      EXPECT_EQ(back.faces, sphere.faces);
    }
    ASSERT_EQ(back.vertices.has_normals(), c.normals);
    if (c.normals) {
      EXPECT_LE((back.vertices.normals - sphere.vertices.normals).cwiseAbs().maxCoeff(), 1e-6);
    }
    ASSERT_EQ(back.vertices.has_colors(), c.colors);
    if (c.colors) {
      EXPECT_EQ(back.vertices.colors, sphere.vertices.colors);
    }
    ASSERT_EQ(back.vertices.scalars.count("height"), c.scalars ? 1u : 0u);
    if (c.scalars) {
      EXPECT_LE(
          (back.vertices.scalars.at("height") - sphere.vertices.scalars.at("height")).cwiseAbs().maxCoeff(),
          1e-4);
    }
  }
}

TEST(MeshIo, InputUnitsScaleToMillimetresAndImplausibleSizesWarn) {
  // A 200 mm sphere stored in metres, as the Stanford scans are.
  TriangleMesh metres = testing::MakeSphere(0.1, Eigen::Vector3d(0.01, 0.02, 0.03));
  const testing::TempDir dir;
  const std::filesystem::path path = dir / "in_metres.ply";
  WriteMesh(path, metres);
  const bool quiet = IsQuiet();
  SetQuiet(true);

  const WarningCollector collector;
  const TriangleMesh mm = ReadMesh(path, ReadOptions{.input_units = LengthUnit::kMetre});
  EXPECT_TRUE(collector.warnings().empty());
  const Bounds3 b = ComputeBounds(mm.vertices.positions);
  EXPECT_NEAR(b.extent().x(), 200.0, 1e-3);
  EXPECT_NEAR(b.extent().z(), 200.0, 1e-3);
  EXPECT_NEAR(mm.vertices.positions(0, 2), 1000 * (0.03 + 0.1), 1e-3);  // the north pole
  // Normals are directions and are not scaled.
  EXPECT_NEAR(mm.vertices.normals.row(0).norm(), 1.0, 1e-6);

  // Read as millimetres the object is 0.2 mm across: a warning names the file and the likely unit.
  const TriangleMesh as_mm = ReadMesh(path);
  ASSERT_EQ(collector.warnings().size(), 1u);
  const std::string warning = collector.warnings()[0];
  EXPECT_NE(warning.find(path.string()), std::string::npos) << warning;
  EXPECT_NE(warning.find("--input-units m"), std::string::npos) << warning;
  EXPECT_LT((as_mm.vertices.positions - metres.vertices.positions).cwiseAbs().maxCoeff(), 1e-7);

  ReadMesh(path, ReadOptions{.input_units = LengthUnit::kMillimetre, .warn_units = false});
  EXPECT_EQ(collector.warnings().size(), 1u);
  SetQuiet(quiet);
}

TEST(MeshIo, ReadPointCloudDropsFaces) {
  const TriangleMesh sphere = testing::MakeSphere();
  const testing::TempDir dir;
  WriteMesh(dir / "s.obj", sphere);
  const PointCloud cloud = ReadPointCloud(dir / "s.obj");
  EXPECT_EQ(cloud.positions, sphere.vertices.positions);
  WritePointCloud(dir / "cloud.ply", cloud);
  EXPECT_EQ(ReadMesh(dir / "cloud.ply").num_faces(), 0);
}

TEST(MeshIo, ErrorsNameTheFile) {
  const testing::TempDir dir;
  EXPECT_TRUE(ThrowsBadInput([&] { ReadMesh(dir.Write("empty.stl", "")); }, "file is empty", "empty.stl"));
  EXPECT_TRUE(ThrowsBadInput([&] { ReadMesh(dir / "missing.ply"); }, "", "missing.ply"));
  EXPECT_TRUE(ThrowsBadInput([&] { ReadMesh(dir.Write("nan.xyz", "1 2 3\n4 nan 6\n")); }, "non-finite",
                             "nan.xyz", 2));
  EXPECT_TRUE(
      ThrowsBadInput([&] { ReadMesh(dir.Write("range.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n")); },
                     "out of range", "range.obj", 4));

  // A point cloud has no triangles for STL; PCD is read-only. Both are usage errors and write nothing.
  TriangleMesh cloud = testing::MakeSphere();
  cloud.faces.resize(0, 3);
  EXPECT_EQ(KindOf([&] { WriteMesh(dir / "cloud.stl", cloud); }), ErrorKind::kUsage);
  EXPECT_EQ(KindOf([&] { WriteMesh(dir / "cloud.pcd", cloud); }), ErrorKind::kUsage);
  EXPECT_FALSE(std::filesystem::exists(dir / "cloud.stl"));
  EXPECT_FALSE(std::filesystem::exists(dir / "cloud.pcd"));
}

}  // namespace
}  // namespace pectus
