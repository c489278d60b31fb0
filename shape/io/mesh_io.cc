#include "shape/io/mesh_io.h"

#include <algorithm>
#include <cctype>

#include "shape/core/atomic_file.h"
#include "shape/core/error.h"
#include "shape/core/log.h"
#include "shape/io/format_parsers.h"
#include "shape/io/mapped_file.h"

namespace pectus {
namespace fs = std::filesystem;

FileFormat FormatFromPath(const fs::path& path) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  if (ext == ".ply") return FileFormat::kPly;
  if (ext == ".obj") return FileFormat::kObj;
  if (ext == ".stl") return FileFormat::kStl;
  if (ext == ".pcd") return FileFormat::kPcd;
  if (ext == ".xyz" || ext == ".txt" || ext == ".pts") return FileFormat::kXyz;
  if (ext == ".csv") return FileFormat::kCsv;
  ThrowUsage(path.string() + ": unknown file type '" + ext +
             "' (pectus reads .ply .obj .stl .pcd .xyz .csv and writes .ply .obj .stl .xyz .csv)");
}

std::string ToString(FileFormat format) {
  switch (format) {
    case FileFormat::kPly: return "ply";
    case FileFormat::kObj: return "obj";
    case FileFormat::kStl: return "stl";
    case FileFormat::kPcd: return "pcd";
    case FileFormat::kXyz: return "xyz";
    case FileFormat::kCsv: return "csv";
  }
  return "?";
}

TriangleMesh ReadMesh(const fs::path& path, const ReadOptions& options, FileSummary* summary) {
  const std::string name = path.string();
  const FileFormat format = FormatFromPath(path);
  TriangleMesh mesh;
  {
    MappedFile file(name);
    if (file.bytes().empty()) ThrowBadInput(name, "file is empty");
    switch (format) {
      case FileFormat::kPly: mesh = ParsePly(file.bytes(), name, summary); break;
      case FileFormat::kObj: mesh = ParseObj(file.bytes(), name, summary); break;
      case FileFormat::kStl: mesh = ParseStl(file.bytes(), name, summary); break;
      case FileFormat::kPcd: mesh = ParsePcd(file.bytes(), name, summary); break;
      default: mesh = ParseXyz(file.bytes(), name, summary); break;
    }
  }
  mesh.Validate(name);
  if (options.warn_units) {
    const std::string warning =
        UnitsWarning(name, ComputeBounds(mesh.vertices.positions), options.input_units);
    if (!warning.empty()) Warn(warning);
  }
  const double scale = MillimetresPer(options.input_units);
  if (scale != 1.0) mesh.vertices.positions *= scale;
  return mesh;
}

PointCloud ReadPointCloud(const fs::path& path, const ReadOptions& options) {
  return std::move(ReadMesh(path, options).vertices);
}

void WriteMesh(const fs::path& path, const TriangleMesh& mesh, const WriteOptions& options) {
  const FileFormat format = FormatFromPath(path);
  if (format == FileFormat::kStl && mesh.num_faces() == 0) {
    ThrowUsage(path.string() + ": STL holds triangles only and this is a point cloud; write .ply instead");
  }
  if (format == FileFormat::kPcd)
    ThrowUsage(path.string() + ": pectus reads PCD but does not write it; use .ply");
  AtomicOutput out(path);
  switch (format) {
    case FileFormat::kPly: WritePly(out.stream(), mesh, options); break;
    case FileFormat::kObj: WriteObj(out.stream(), mesh, options); break;
    case FileFormat::kStl: WriteStl(out.stream(), mesh, options); break;
    case FileFormat::kCsv: WriteXyz(out.stream(), mesh, ',', options); break;
    default: WriteXyz(out.stream(), mesh, ' ', options); break;
  }
  out.Commit();
}

void WritePointCloud(const fs::path& path, const PointCloud& cloud, const WriteOptions& options) {
  TriangleMesh mesh;
  mesh.vertices = cloud;
  mesh.faces.resize(0, 3);
  WriteMesh(path, mesh, options);
}

}  // namespace pectus
