// pectus: the PCD format's internals shared by the reader's two parts, pcd_header.cc (the header) and
// pcd_io.cc (the data). Not a public header: include format_parsers.h instead.
//
// A PCD file (PCL's Point Cloud Data, versions 0.5 to 0.7) is a text header, one keyword a line
// (VERSION, FIELDS, SIZE, TYPE, COUNT, WIDTH, HEIGHT, VIEWPOINT, POINTS, DATA), then the points:
//   ascii              one point a line, every element of every field as a number;
//   binary             point after point, each the fields' elements in order (little endian);
//   binary_compressed  uint32 compressed size, uint32 uncompressed size, then LZF data that expands to
//                      field after field (all points' x, then all points' y, ...), padding fields ("_")
//                      left out.
// The header is checked against the size of the data before anything is allocated or read: a header that
// lies about its counts gives an error naming the file, not a huge allocation or a read past the end.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace pectus::pcd {

/// A field's element type: TYPE (I signed, U unsigned, F floating point) with SIZE (bytes).
enum class Type : std::uint8_t {
  kInt8,
  kUint8,
  kInt16,
  kUint16,
  kInt32,
  kUint32,
  kInt64,
  kUint64,
  kFloat32,
  kFloat64
};

/// "char", "uchar", ..., "float", "double": the names `pectus info` shows, as for PLY.
std::string TypeName(Type type);

/// One field of a point: `count` elements of `type`, `size` bytes each.
struct Field {
  std::string name;
  Type type = Type::kFloat32;
  std::uint64_t size = 4;    ///< bytes of one element: 1, 2, 4 or 8
  std::uint64_t count = 1;   ///< elements (1 for a scalar; 33 for an FPFH descriptor)
  std::uint64_t offset = 0;  ///< bytes from the start of a binary point to this field

  std::uint64_t bytes() const { return size * count; }
  /// PCL writes padding as fields named "_": bytes without a value.
  bool is_padding() const { return name == "_"; }
};

enum class Encoding { kAscii, kBinary, kBinaryCompressed };

/// What the header declares, checked for consistency and against the size of the data.
struct Header {
  std::string version;                 ///< "0.5", "0.6" or "0.7"; empty if the file has no VERSION line
  std::vector<Field> fields;           ///< in the order of FIELDS
  std::uint64_t width = 0;             ///< points per row (all points for an unorganized cloud)
  std::uint64_t height = 1;            ///< rows (1 for an unorganized cloud)
  std::uint64_t points = 0;            ///< width x height
  std::uint64_t point_bytes = 0;       ///< one binary point: the sum of the fields' bytes
  std::uint64_t values_per_point = 0;  ///< one ascii point: the sum of the fields' counts
  Encoding encoding = Encoding::kAscii;
  std::size_t data_offset = 0;  ///< the first byte after the DATA line
  std::int64_t data_line = 0;   ///< the 1-based line number of that byte (for ascii errors)
  /// binary_compressed only: the LZF block's sizes, as its first 8 bytes give them.
  std::uint32_t compressed_bytes = 0;
  std::uint32_t uncompressed_bytes = 0;
};

/// Parses and checks the header of the PCD file `bytes`; throws Error(kBadInput) naming `name` (and the
/// line) for anything malformed or for data shorter than the header declares.
Header ParseHeader(std::string_view bytes, const std::string& name);

}  // namespace pectus::pcd
