// pectus: read and write point clouds and meshes in any supported format, chosen by file extension.
#pragma once

#include <filesystem>
#include <string>

#include "shape/core/geometry.h"
#include "shape/core/units.h"
#include "shape/io/file_summary.h"

namespace pectus {

/// File formats pectus reads (all) and writes (PLY, STL, OBJ, XYZ, CSV).
enum class FileFormat { kPly, kObj, kStl, kPcd, kXyz, kCsv };

/// The format named by the path's extension (case-insensitive); throws Error(kUsage) for an unknown one.
FileFormat FormatFromPath(const std::filesystem::path& path);
std::string ToString(FileFormat format);

/// Options for reading any geometry file.
struct ReadOptions {
  LengthUnit input_units = LengthUnit::kMillimetre;  ///< unit of the file's coordinates; scaled to mm
  bool warn_units = true;  ///< warn (pectus::Warn) when the object's size makes the unit look wrong
};

/// Reads any supported file. A point cloud comes back as a mesh without faces. Polygons are split into
/// triangles (fan). Throws Error(kBadInput) naming the file (and line) for anything malformed, including
/// NaN or Inf coordinates and face indices out of range.
/// @param[out] summary  if not null, the file's structure (elements, counts, properties)
TriangleMesh ReadMesh(const std::filesystem::path& path, const ReadOptions& options = {},
                      FileSummary* summary = nullptr);
/// ReadMesh without the faces.
PointCloud ReadPointCloud(const std::filesystem::path& path, const ReadOptions& options = {});

/// Options for writing.
struct WriteOptions {
  bool binary = true;   ///< PLY and STL: binary (default) or ASCII
  std::string comment;  ///< written into the header where the format has one
};

/// Writes a mesh (or, with no faces, a point cloud) atomically; the format comes from the extension.
/// PLY keeps normals, colours and every scalar; OBJ keeps normals; STL keeps triangles only (a point
/// cloud cannot be written as STL: Error(kUsage)).
void WriteMesh(const std::filesystem::path& path, const TriangleMesh& mesh, const WriteOptions& options = {});
void WritePointCloud(const std::filesystem::path& path, const PointCloud& cloud,
                     const WriteOptions& options = {});

}  // namespace pectus
