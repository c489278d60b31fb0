// pectus: the parsers and writers behind mesh_io.h, one per format. Each parser reads from memory, so
// that files (memory-mapped) and fuzzers use the same code. `name` is the file name used in errors.
#pragma once

#include <ostream>
#include <string>
#include <string_view>

#include "shape/core/geometry.h"
#include "shape/io/file_summary.h"
#include "shape/io/mesh_io.h"

namespace pectus {

/// PLY: ASCII, binary little and big endian; any element and property types; elements other than
/// vertex and face are skipped. Vertex properties x y z, nx ny nz, red green blue (uchar or float),
/// and every other scalar property kept as a named scalar. Faces from `vertex_indices` or `vertex_index`.
TriangleMesh ParsePly(std::string_view bytes, const std::string& name, FileSummary* summary = nullptr);
/// PLY writer: binary little endian or ASCII; positions as float (double if any |coordinate| > 1e5 so
/// that far-from-origin data keeps sub-millimetre precision), normals, colours, scalars as float.
void WritePly(std::ostream& out, const TriangleMesh& mesh, const WriteOptions& options);

/// Wavefront OBJ: v, vn, f (v, v/vt, v//vn, v/vt/vn, negative indices), polygons fanned into triangles.
TriangleMesh ParseObj(std::string_view bytes, const std::string& name, FileSummary* summary = nullptr);
void WriteObj(std::ostream& out, const TriangleMesh& mesh, const WriteOptions& options);

/// STL: ASCII and binary (told apart by content, not the first word); identical vertices are welded.
TriangleMesh ParseStl(std::string_view bytes, const std::string& name, FileSummary* summary = nullptr);
void WriteStl(std::ostream& out, const TriangleMesh& mesh, const WriteOptions& options);

/// XYZ / CSV: one point per line, separated by spaces, tabs, commas or semicolons; x y z, optionally
/// followed by nx ny nz; an optional header line of names (x,y,z,nx,ny,nz,...; other columns become
/// scalars); lines starting with # are comments.
TriangleMesh ParseXyz(std::string_view bytes, const std::string& name, FileSummary* summary = nullptr);
void WriteXyz(std::ostream& out, const TriangleMesh& mesh, char separator, const WriteOptions& options);

/// PCD (PCL's Point Cloud Data, versions 0.5-0.7; ascii, binary, binary_compressed): fields x y z of any
/// type, normal_x normal_y normal_z, a packed rgb or rgba (4 bytes), and every other one-element field
/// kept as a named scalar (padding "_" and multi-element fields such as descriptors are not). Points with
/// a NaN position (the gaps of an organized cloud) are left out with a warning. pcd_format.h says how.
TriangleMesh ParsePcd(std::string_view bytes, const std::string& name, FileSummary* summary = nullptr);

}  // namespace pectus
