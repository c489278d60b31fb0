// pectus: the PLY format's internals shared by the reader's parts (ply_header.cc, ply_ascii.cc,
// ply_binary.cc) and the writer (ply_io.cc). Not a public header: include format_parsers.h instead.
//
// The reader works on the whole file in memory (which is not NUL-terminated and may hold any bytes):
//   1. the header is parsed into elements and their properties (ply_header.cc);
//   2. each element in turn is checked to fit in the bytes that are left before anything is reserved
//      (so a header that lies about its counts gives an error, not a huge allocation);
//   3. vertex and face elements are read, every other element is skipped (ply_ascii.cc, ply_binary.cc).
// Binary vertices without list properties are fixed-size records: each wanted property is copied column
// by column from its byte offset, a block of records at a time, with a byte swap for big endian.
#pragma once

#include <algorithm>
#include <bit>
#include <cstdint>
#include <cstring>
#include <optional>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include "shape/core/geometry.h"
#include "shape/io/file_summary.h"

namespace pectus::ply {

// ------------------------------------------------------------------------------------------------
// Property types and raw loads.

/// A PLY property type.
enum class Type : std::uint8_t { kInt8, kUint8, kInt16, kUint16, kInt32, kUint32, kFloat32, kFloat64 };

inline std::optional<Type> TypeFromName(std::string_view s) {
  if (s == "char" || s == "int8") return Type::kInt8;
  if (s == "uchar" || s == "uint8") return Type::kUint8;
  if (s == "short" || s == "int16") return Type::kInt16;
  if (s == "ushort" || s == "uint16") return Type::kUint16;
  if (s == "int" || s == "int32") return Type::kInt32;
  if (s == "uint" || s == "uint32") return Type::kUint32;
  if (s == "float" || s == "float32") return Type::kFloat32;
  if (s == "double" || s == "float64") return Type::kFloat64;
  return std::nullopt;
}

inline std::size_t SizeOf(Type t) {
  switch (t) {
    case Type::kInt8:
    case Type::kUint8: return 1;
    case Type::kInt16:
    case Type::kUint16: return 2;
    case Type::kInt32:
    case Type::kUint32:
    case Type::kFloat32: return 4;
    case Type::kFloat64: return 8;
  }
  return 1;
}

inline bool IsInteger(Type t) { return t != Type::kFloat32 && t != Type::kFloat64; }

/// Calls fn(std::type_identity<T>{}) with the C++ type T of `t`.
template <typename Fn>
decltype(auto) WithType(Type t, Fn&& fn) {
  switch (t) {
    case Type::kInt8: return fn(std::type_identity<std::int8_t>{});
    case Type::kUint8: return fn(std::type_identity<std::uint8_t>{});
    case Type::kInt16: return fn(std::type_identity<std::int16_t>{});
    case Type::kUint16: return fn(std::type_identity<std::uint16_t>{});
    case Type::kInt32: return fn(std::type_identity<std::int32_t>{});
    case Type::kUint32: return fn(std::type_identity<std::uint32_t>{});
    case Type::kFloat32: return fn(std::type_identity<float>{});
    case Type::kFloat64: break;
  }
  return fn(std::type_identity<double>{});
}

inline std::uint16_t ByteSwap(std::uint16_t v) { return __builtin_bswap16(v); }
inline std::uint32_t ByteSwap(std::uint32_t v) { return __builtin_bswap32(v); }
inline std::uint64_t ByteSwap(std::uint64_t v) { return __builtin_bswap64(v); }

template <std::size_t N>
using UintOfSize =
    std::conditional_t<N == 2, std::uint16_t, std::conditional_t<N == 4, std::uint32_t, std::uint64_t>>;

/// Reads a T stored at p (any alignment), byte-swapped if kSwap.
template <typename T, bool kSwap>
inline T Load(const char* p) {
  if constexpr (sizeof(T) == 1) {
    T v;
    std::memcpy(&v, p, 1);
    return v;
  } else {
    UintOfSize<sizeof(T)> u;
    std::memcpy(&u, p, sizeof(u));
    if constexpr (kSwap) u = ByteSwap(u);
    return std::bit_cast<T>(u);
  }
}

inline double LoadAsDouble(const char* p, Type t, bool swap) {
  return WithType(t, [&](auto tag) {
    using T = typename decltype(tag)::type;
    return swap ? static_cast<double>(Load<T, true>(p)) : static_cast<double>(Load<T, false>(p));
  });
}

/// Writes v at p in little-endian byte order.
template <typename T>
inline void StoreLittleEndian(char* p, T v) {
  if constexpr (sizeof(T) == 1 || std::endian::native == std::endian::little) {
    std::memcpy(p, &v, sizeof(T));
  } else {
    const auto u = ByteSwap(std::bit_cast<UintOfSize<sizeof(T)>>(v));
    std::memcpy(p, &u, sizeof(T));
  }
}

/// An 8-bit colour channel from a stored value: integers are clamped to 0..255, floats scaled from 0..1.
inline std::uint8_t ColorFromValue(double v, bool is_integer) {
  if (!is_integer) v = v * 255.0 + 0.5;
  if (!(v > 0)) return 0;  // also NaN
  if (v >= 255) return 255;
  return static_cast<std::uint8_t>(v);
}

// ------------------------------------------------------------------------------------------------
// Header.

/// How the data after the header is stored.
enum class Encoding { kAscii, kBinaryLittleEndian, kBinaryBigEndian };

/// One property of an element as the header declares it.
struct Property {
  std::string name;
  Type type = Type::kFloat32;  ///< value type; for a list, the type of its items
  bool is_list = false;
  Type count_type = Type::kUint8;  ///< for a list, the type of its length
  std::string declaration;         ///< "float x", "list uchar int vertex_indices"
};

/// One element of the header (vertex, face, range_grid, ...) with its properties.
struct Element {
  std::string name;
  std::int64_t count = 0;
  std::int64_t header_line = 0;  ///< 1-based line of its "element" line
  std::vector<Property> properties;

  bool HasList() const {
    return std::any_of(properties.begin(), properties.end(), [](const Property& p) { return p.is_list; });
  }
  /// Bytes per binary record, counting each list as its length field only.
  std::size_t MinBinarySize() const {
    std::size_t size = 0;
    for (const Property& p : properties) size += p.is_list ? SizeOf(p.count_type) : SizeOf(p.type);
    return size;
  }
  int FindProperty(std::string_view property_name) const {
    for (std::size_t i = 0; i < properties.size(); ++i) {
      if (properties[i].name == property_name) return static_cast<int>(i);
    }
    return -1;
  }
};

/// The parsed header of a PLY file.
struct Header {
  Encoding encoding = Encoding::kAscii;
  std::vector<Element> elements;
  std::size_t data_offset = 0;  ///< first byte after the end_header line
  std::int64_t line_count = 0;  ///< lines in the header, end_header included
};

inline bool IsBlank(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

/// `text` made printable and short, to quote in a message.
std::string Quote(std::string_view text);
/// The blank-separated words of a line.
std::vector<std::string_view> SplitWords(std::string_view line);
/// Parses the header of the PLY file `bytes` (named `name` in errors); fills `summary` if not null.
Header ParseHeader(std::string_view bytes, const std::string& name, FileSummary* summary);
/// Asks the kernel to back a new buffer of `bytes` with huge pages: filling 100 MB of output then takes
/// 50 page faults instead of 25000, which is a third of the time of reading a binary file.
void AdviseHugePages(void* data, std::size_t bytes);

// ------------------------------------------------------------------------------------------------
// What to do with each vertex property.

/// Where one vertex property goes in the point cloud being filled.
struct Slot {
  enum class Kind : std::uint8_t { kIgnore, kValue, kColor };
  Kind kind = Kind::kIgnore;
  Type type = Type::kFloat32;
  bool is_list = false;
  Type count_type = Type::kUint8;
  std::size_t offset = 0;          ///< byte offset inside a fixed-size binary record
  double* values = nullptr;        ///< kValue: where item 0 goes
  std::uint8_t* colors = nullptr;  ///< kColor: where item 0 goes
  std::ptrdiff_t stride = 1;       ///< distance between items in values / colors
  const Property* property = nullptr;
};

/// Column k of the first row of an #items by 3 matrix, or null if it is empty (and has no data).
template <typename Matrix>
auto* Column(Matrix* m, int k) {
  return m->size() > 0 ? m->data() + k : nullptr;
}

/// The vertex properties mapped into `cloud` (resized to the vertex count): x y z, nx ny nz,
/// red green blue (or diffuse_red ...), alpha ignored, every other scalar kept as a named scalar.
std::vector<Slot> MapVertexProperties(const Element& vertex, const std::string& name, PointCloud* cloud);

inline void Apply(const Slot& s, Eigen::Index item, double v) {
  if (s.kind == Slot::Kind::kValue) {
    s.values[item * s.stride] = v;
  } else if (s.kind == Slot::Kind::kColor) {
    s.colors[item * s.stride] = ColorFromValue(v, IsInteger(s.type));
  }
}

/// Appends triangles to a #faces by 3 matrix, growing it geometrically.
class FaceSink {
 public:
  explicit FaceSink(Eigen::Index reserve) {
    faces_.resize(std::max<Eigen::Index>(reserve, 1), 3);
    AdviseHugePages(faces_.data(), sizeof(std::int32_t) * faces_.size());
  }
  void Add(std::int32_t a, std::int32_t b, std::int32_t c) {
    if (size_ == faces_.rows()) faces_.conservativeResize(2 * size_, 3);
    std::int32_t* row = faces_.data() + 3 * size_;
    row[0] = a, row[1] = b, row[2] = c;
    ++size_;
  }
  /// Triangles fanned from a polygon v[0..n).
  template <typename Index>
  void AddPolygon(const Index* v, std::int64_t n) {
    for (std::int64_t j = 1; j + 1 < n; ++j) {
      Add(static_cast<std::int32_t>(v[0]), static_cast<std::int32_t>(v[j]),
          static_cast<std::int32_t>(v[j + 1]));
    }
  }
  Faces3 Finish() {
    faces_.conservativeResize(size_, 3);
    return std::move(faces_);
  }

 private:
  Faces3 faces_;
  Eigen::Index size_ = 0;
};

/// "vertices", "faces" or "'name' items", for messages.
std::string Plural(const Element& e);
/// "vertex", "face" or "'name' item", for messages.
std::string Singular(const Element& e);
/// "property 'x' of vertex 12", for messages.
std::string PropertyOf(const Property& p, const Element& e, std::int64_t item);

/// Where the vertex and face elements are, for the readers of the data.
struct Layout {
  const Element* vertex = nullptr;  ///< the vertex element
  const Element* face = nullptr;    ///< the face element, or null
  int index_property = -1;          ///< the face element's vertex index list
};

/// Reads the data of an ASCII file (the bytes after the header) into `mesh` (vertices) and `faces`.
void ReadAsciiData(std::string_view data, const Header& header, const Layout& layout, const std::string& name,
                   TriangleMesh* mesh, Faces3* faces);
/// Reads the data of a binary file (the bytes after the header) into `mesh` (vertices) and `faces`.
void ReadBinaryData(std::string_view data, const Header& header, const Layout& layout,
                    const std::string& name, TriangleMesh* mesh, Faces3* faces);

}  // namespace pectus::ply
