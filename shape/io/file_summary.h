// pectus: what a geometry file holds, as `pectus info` shows it.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace pectus {

/// One element of a file (PLY element, or the implied "vertex"/"face" of other formats).
struct ElementSummary {
  std::string name;                     ///< "vertex", "face", "range_grid", ...
  std::int64_t count = 0;               ///< as the file declares (or as parsed, where nothing is declared)
  std::vector<std::string> properties;  ///< "float x", "list uchar int vertex_indices", ...
};

/// The structure of a file, filled in by the parsers.
struct FileSummary {
  std::string format;    ///< "ply", "obj", "stl", "pcd", "xyz", "csv"
  std::string encoding;  ///< "ascii", "binary_little_endian", "binary_big_endian", "binary"
  std::vector<ElementSummary> elements;
  std::vector<std::string> comments;  ///< header comments and obj_info lines
};

}  // namespace pectus
