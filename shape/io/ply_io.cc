// pectus: PLY reader and writer (ASCII, binary little endian, binary big endian).
//
// The reader works on the whole file in memory (which is not NUL-terminated and may hold any bytes):
//   1. the header is parsed into elements and their properties;
//   2. each element in turn is checked to fit in the bytes that are left before anything is reserved
//      (so a header that lies about its counts gives an error, not a huge allocation);
//   3. vertex and face elements are read, every other element is skipped.
// Binary vertices without list properties are fixed-size records: each wanted property is copied column
// by column from its byte offset, a block of records at a time, with a byte swap for big endian.
#include <algorithm>
#include <bit>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <system_error>
#include <type_traits>
#include <vector>

#if defined(__linux__)
#include <sys/mman.h>
#endif

#include "shape/core/error.h"
#include "shape/io/format_parsers.h"

namespace pectus {
namespace {

// ------------------------------------------------------------------------------------------------
// Property types and raw loads.

enum class Type : std::uint8_t { kInt8, kUint8, kInt16, kUint16, kInt32, kUint32, kFloat32, kFloat64 };

std::optional<Type> TypeFromName(std::string_view s) {
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

std::size_t SizeOf(Type t) {
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

bool IsInteger(Type t) { return t != Type::kFloat32 && t != Type::kFloat64; }

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

double LoadAsDouble(const char* p, Type t, bool swap) {
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

enum class Encoding { kAscii, kBinaryLittleEndian, kBinaryBigEndian };

struct Property {
  std::string name;
  Type type = Type::kFloat32;        ///< value type; for a list, the type of its items
  bool is_list = false;
  Type count_type = Type::kUint8;    ///< for a list, the type of its length
  std::string declaration;           ///< "float x", "list uchar int vertex_indices"
};

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

struct Header {
  Encoding encoding = Encoding::kAscii;
  std::vector<Element> elements;
  std::size_t data_offset = 0;   ///< first byte after the end_header line
  std::int64_t line_count = 0;   ///< lines in the header, end_header included
};

bool IsBlank(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

/// `text` made printable and short, to quote in a message.
std::string Quote(std::string_view text) {
  std::string out = "'";
  for (std::size_t i = 0; i < text.size() && i < 40; ++i) {
    const auto c = static_cast<unsigned char>(text[i]);
    out += (c >= 32 && c < 127) ? static_cast<char>(c) : '?';
  }
  if (text.size() > 40) out += "...";
  return out + "'";
}

std::vector<std::string_view> SplitWords(std::string_view line) {
  std::vector<std::string_view> words;
  std::size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && IsBlank(line[i])) ++i;
    const std::size_t start = i;
    while (i < line.size() && !IsBlank(line[i])) ++i;
    if (i > start) words.push_back(line.substr(start, i - start));
  }
  return words;
}

Header ParseHeader(std::string_view bytes, const std::string& name, FileSummary* summary) {
  if (bytes.empty()) ThrowBadInput(name, "file is empty");
  Header header;
  std::size_t pos = 0;
  std::int64_t line_number = 0;
  // The next line without its end-of-line characters; false at the end of the bytes.
  auto next_line = [&](std::string_view* line) {
    if (pos >= bytes.size()) return false;
    const char* begin = bytes.data() + pos;
    const std::size_t rest = bytes.size() - pos;
    const auto* newline = static_cast<const char*>(std::memchr(begin, '\n', rest));
    std::size_t length = newline != nullptr ? static_cast<std::size_t>(newline - begin) : rest;
    pos += newline != nullptr ? length + 1 : length;
    ++line_number;
    while (length > 0 && IsBlank(begin[length - 1])) --length;
    *line = std::string_view(begin, length);
    return true;
  };

  std::string_view line;
  next_line(&line);
  if (line != "ply") {
    ThrowBadInput(name, "not a PLY file: the first line must be 'ply' but is " + Quote(line), 1);
  }
  bool have_format = false;
  while (true) {
    if (!next_line(&line)) {
      ThrowBadInput(name, "missing end_header: the PLY header never ends", line_number);
    }
    const std::vector<std::string_view> words = SplitWords(line);
    if (words.empty()) continue;
    const std::string_view keyword = words[0];
    if (keyword == "end_header") {
      if (words.size() != 1) ThrowBadInput(name, "unexpected text after end_header", line_number);
      break;
    }
    if (keyword == "comment" || keyword == "obj_info") {
      if (summary != nullptr) {
        std::string_view text = line.substr(line.find(keyword) + keyword.size());
        while (!text.empty() && IsBlank(text.front())) text.remove_prefix(1);
        summary->comments.push_back(keyword == "comment" ? std::string(text)
                                                         : "obj_info " + std::string(text));
      }
      continue;
    }
    if (keyword == "format") {
      if (have_format) ThrowBadInput(name, "second format line", line_number);
      if (words.size() != 3) ThrowBadInput(name, "format line must read 'format <encoding> 1.0'", line_number);
      if (words[1] == "ascii") {
        header.encoding = Encoding::kAscii;
      } else if (words[1] == "binary_little_endian") {
        header.encoding = Encoding::kBinaryLittleEndian;
      } else if (words[1] == "binary_big_endian") {
        header.encoding = Encoding::kBinaryBigEndian;
      } else {
        ThrowBadInput(name,
                      "unknown format " + Quote(words[1]) +
                          " (expected ascii, binary_little_endian or binary_big_endian)",
                      line_number);
      }
      if (words[2] != "1.0" && words[2] != "1") {
        ThrowBadInput(name, "unsupported PLY version " + Quote(words[2]) + " (expected 1.0)", line_number);
      }
      have_format = true;
      continue;
    }
    if (keyword == "element") {
      if (words.size() != 3) ThrowBadInput(name, "element line must read 'element <name> <count>'", line_number);
      Element element;
      element.name = std::string(words[1]);
      element.header_line = line_number;
      const std::string_view count = words[2];
      const auto [end, ec] = std::from_chars(count.data(), count.data() + count.size(), element.count);
      if (ec != std::errc() || end != count.data() + count.size() || element.count < 0) {
        ThrowBadInput(name, "invalid count " + Quote(count) + " for element " + Quote(words[1]), line_number);
      }
      for (const Element& other : header.elements) {
        if (other.name == element.name) {
          ThrowBadInput(name, "element " + Quote(element.name) + " is declared twice", line_number);
        }
      }
      header.elements.push_back(std::move(element));
      continue;
    }
    if (keyword == "property") {
      if (header.elements.empty()) ThrowBadInput(name, "property line before any element line", line_number);
      Element& element = header.elements.back();
      Property property;
      const bool is_list = words.size() >= 2 && words[1] == "list";
      if (is_list ? words.size() != 5 : words.size() != 3) {
        ThrowBadInput(name,
                      "property line must read 'property <type> <name>' or "
                      "'property list <count type> <item type> <name>'",
                      line_number);
      }
      property.name = std::string(words.back());
      property.is_list = is_list;
      const std::string_view type_name = is_list ? words[3] : words[1];
      const std::optional<Type> type = TypeFromName(type_name);
      if (!type) {
        ThrowBadInput(name,
                      "unknown property type " + Quote(type_name) + " for property " + Quote(property.name) +
                          " of element " + Quote(element.name),
                      line_number);
      }
      property.type = *type;
      if (is_list) {
        const std::optional<Type> count_type = TypeFromName(words[2]);
        if (!count_type) {
          ThrowBadInput(name,
                        "unknown property type " + Quote(words[2]) + " for the length of list " +
                            Quote(property.name) + " of element " + Quote(element.name),
                        line_number);
        }
        if (!IsInteger(*count_type)) {
          ThrowBadInput(name, "the length of list " + Quote(property.name) + " must have an integer type",
                        line_number);
        }
        property.count_type = *count_type;
        property.declaration = "list " + std::string(words[2]) + " " + std::string(words[3]) + " " + property.name;
      } else {
        property.declaration = std::string(words[1]) + " " + property.name;
      }
      if (element.FindProperty(property.name) >= 0) {
        ThrowBadInput(name,
                      "property " + Quote(property.name) + " of element " + Quote(element.name) +
                          " is declared twice",
                      line_number);
      }
      element.properties.push_back(std::move(property));
      continue;
    }
    ThrowBadInput(name, "unknown header line " + Quote(line), line_number);
  }
  if (!have_format) ThrowBadInput(name, "the PLY header has no format line", line_number);
  header.data_offset = pos;
  header.line_count = line_number;

  if (summary != nullptr) {
    summary->format = "ply";
    summary->encoding = header.encoding == Encoding::kAscii                ? "ascii"
                        : header.encoding == Encoding::kBinaryLittleEndian ? "binary_little_endian"
                                                                           : "binary_big_endian";
    for (const Element& element : header.elements) {
      ElementSummary& s = summary->elements.emplace_back();
      s.name = element.name;
      s.count = element.count;
      for (const Property& p : element.properties) s.properties.push_back(p.declaration);
    }
  }
  return header;
}

/// Asks the kernel to back a new buffer of `bytes` with huge pages: filling 100 MB of output then takes
/// 50 page faults instead of 25000, which is a third of the time of reading a binary file.
void AdviseHugePages(void* data, std::size_t bytes) {
#if defined(__linux__) && defined(MADV_HUGEPAGE)
  constexpr std::uintptr_t kHuge = std::uintptr_t{2} << 20;
  if (bytes < 2 * kHuge) return;
  const std::uintptr_t begin = (reinterpret_cast<std::uintptr_t>(data) + kHuge - 1) & ~(kHuge - 1);
  const std::uintptr_t end = (reinterpret_cast<std::uintptr_t>(data) + bytes) & ~(kHuge - 1);
  if (end > begin) ::madvise(reinterpret_cast<void*>(begin), end - begin, MADV_HUGEPAGE);
#else
  (void)data, (void)bytes;
#endif
}

// ------------------------------------------------------------------------------------------------
// What to do with each vertex property.

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
std::vector<Slot> MapVertexProperties(const Element& vertex, const std::string& name, PointCloud* cloud) {
  const Eigen::Index n = vertex.count;
  auto find_scalar = [&](std::string_view property_name) {
    const int i = vertex.FindProperty(property_name);
    return (i >= 0 && !vertex.properties[i].is_list) ? i : -1;
  };
  const int xyz[3] = {find_scalar("x"), find_scalar("y"), find_scalar("z")};
  for (int k = 0; k < 3; ++k) {
    if (xyz[k] < 0) {
      ThrowBadInput(name, std::string("the vertex element has no scalar property '") + "xyz"[k] + "'",
                    vertex.header_line);
    }
  }
  const int normal[3] = {find_scalar("nx"), find_scalar("ny"), find_scalar("nz")};
  const bool has_normals = normal[0] >= 0 && normal[1] >= 0 && normal[2] >= 0;
  int color[3] = {find_scalar("red"), find_scalar("green"), find_scalar("blue")};
  if (color[0] < 0 || color[1] < 0 || color[2] < 0) {
    color[0] = find_scalar("diffuse_red");
    color[1] = find_scalar("diffuse_green");
    color[2] = find_scalar("diffuse_blue");
  }
  const bool has_colors = color[0] >= 0 && color[1] >= 0 && color[2] >= 0;

  cloud->positions.resize(n, 3);
  cloud->normals.resize(has_normals ? n : 0, 3);
  cloud->colors.resize(has_colors ? n : 0, 3);
  AdviseHugePages(cloud->positions.data(), sizeof(double) * cloud->positions.size());
  AdviseHugePages(cloud->normals.data(), sizeof(double) * cloud->normals.size());
  std::vector<Slot> slots(vertex.properties.size());
  std::size_t offset = 0;
  for (std::size_t i = 0; i < slots.size(); ++i) {
    const Property& p = vertex.properties[i];
    Slot& s = slots[i];
    s.type = p.type;
    s.is_list = p.is_list;
    s.count_type = p.count_type;
    s.offset = offset;
    s.property = &p;
    offset += p.is_list ? SizeOf(p.count_type) : SizeOf(p.type);
    if (p.is_list) continue;
    auto to_values = [&s](double* values, std::ptrdiff_t stride) {
      s.kind = Slot::Kind::kValue;
      s.values = values;
      s.stride = stride;
    };
    for (int k = 0; k < 3; ++k) {
      if (static_cast<int>(i) == xyz[k]) {
        to_values(Column(&cloud->positions, k), 3);
      } else if (has_normals && static_cast<int>(i) == normal[k]) {
        to_values(Column(&cloud->normals, k), 3);
      } else if (has_colors && static_cast<int>(i) == color[k]) {
        s.kind = Slot::Kind::kColor;
        s.colors = Column(&cloud->colors, k);
        s.stride = 3;
      }
    }
    if (s.kind != Slot::Kind::kIgnore || p.name == "alpha" || p.name == "diffuse_alpha") continue;
    Eigen::VectorXd& scalar = cloud->scalars[p.name];
    scalar.resize(n);
    AdviseHugePages(scalar.data(), sizeof(double) * scalar.size());
    to_values(scalar.data(), 1);
  }
  return slots;
}

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
      Add(static_cast<std::int32_t>(v[0]), static_cast<std::int32_t>(v[j]), static_cast<std::int32_t>(v[j + 1]));
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

std::string Plural(const Element& e) {
  if (e.name == "vertex") return "vertices";
  if (e.name == "face") return "faces";
  return Quote(e.name) + " items";
}
std::string Singular(const Element& e) {
  if (e.name == "vertex" || e.name == "face") return e.name;
  return Quote(e.name) + " item";
}

// ------------------------------------------------------------------------------------------------
// ASCII data: one item per line, blank lines ignored.

class AsciiReader {
 public:
  enum class Status { kOk, kMissing, kNotANumber, kOutOfRange };

  AsciiReader(std::string_view data, std::int64_t lines_before, const std::string& name)
      : next_(data.data()), end_(data.data() + data.size()), line_(lines_before), name_(name) {}

  /// Moves to the next non-blank line; false at the end of the data.
  bool NextLine() {
    while (next_ < end_) {
      const char* s = next_;
      const auto* newline = static_cast<const char*>(std::memchr(s, '\n', static_cast<std::size_t>(end_ - s)));
      line_end_ = newline != nullptr ? newline : end_;
      next_ = newline != nullptr ? newline + 1 : end_;
      ++line_;
      while (s < line_end_ && IsBlank(*s)) ++s;
      if (s < line_end_) {
        p_ = s;
        return true;
      }
    }
    return false;
  }

  /// Reads the next number of the line as a T (from_chars rules, with an optional leading '+').
  template <typename T>
  Status Read(T* value) {
    while (p_ < line_end_ && IsBlank(*p_)) ++p_;
    token_ = p_;
    if (p_ == line_end_) return Status::kMissing;
    const char* s = p_;
    if (*s == '+') {
      ++s;
      if (s == line_end_ || *s == '-') return Status::kNotANumber;
    }
    const auto [end, ec] = std::from_chars(s, line_end_, *value);
    if (ec == std::errc::invalid_argument || (end < line_end_ && !IsBlank(*end))) return Status::kNotANumber;
    if (ec != std::errc()) return Status::kOutOfRange;
    p_ = end;
    return Status::kOk;
  }

  /// A value of property type t, as a double (float properties are read as float: exact round trip).
  Status ReadValue(Type t, double* value) {
    if (t == Type::kFloat32) {
      float f = 0;
      const Status status = Read(&f);
      *value = f;
      return status;
    }
    return Read(value);
  }

  Status SkipToken() {
    while (p_ < line_end_ && IsBlank(*p_)) ++p_;
    token_ = p_;
    if (p_ == line_end_) return Status::kMissing;
    while (p_ < line_end_ && !IsBlank(*p_)) ++p_;
    return Status::kOk;
  }

  bool AtLineEnd() {
    while (p_ < line_end_ && IsBlank(*p_)) ++p_;
    return p_ == line_end_;
  }

  std::int64_t line() const { return line_; }
  std::size_t bytes_left() const { return static_cast<std::size_t>(end_ - next_); }

  [[noreturn]] void Fail(const std::string& message) const { ThrowBadInput(name_, message, line_); }

  /// Throws for a failed Read of `what` (e.g. "property 'x' of vertex 12").
  [[noreturn]] void FailRead(Status status, const std::string& what) const {
    const char* end = token_;
    while (end < line_end_ && !IsBlank(*end)) ++end;
    const std::string_view token(token_, static_cast<std::size_t>(end - token_));
    switch (status) {
      case Status::kMissing: Fail("the line ends before " + what + " (too few values on the line)");
      case Status::kNotANumber: Fail(what + " is not a number: " + Quote(token));
      default: Fail(what + " is out of range: " + Quote(token));
    }
  }

  /// Throws unless only blank lines remain.
  void ExpectEnd() {
    if (NextLine()) Fail("more data lines than the header declares (line " + std::to_string(line_) + " is extra)");
  }

 private:
  const char* next_;                ///< start of the next line
  const char* end_;                 ///< end of the data
  const char* p_ = nullptr;         ///< read position inside the current line
  const char* line_end_ = nullptr;  ///< end of the current line (before '\n')
  const char* token_ = nullptr;     ///< start of the last token read
  std::int64_t line_;               ///< 1-based number of the current line in the file
  const std::string& name_;
};

std::string PropertyOf(const Property& p, const Element& e, std::int64_t item) {
  return "property " + Quote(p.name) + " of " + Singular(e) + " " + std::to_string(item);
}

/// Checks the vertices can fit in the bytes left before they are allocated.
void CheckAsciiFits(const AsciiReader& in, const Element& e) {
  // Each value takes at least one character and one separator (the last one a line end).
  const std::size_t min_bytes = std::max<std::size_t>(2 * e.properties.size(), 2) - 1;
  if (static_cast<std::uint64_t>(e.count) <= in.bytes_left() / min_bytes) return;
  const std::string declared = "the header declares " + std::to_string(e.count) + " " + Plural(e) + " but only " +
                               std::to_string(in.bytes_left()) + " bytes of data remain";
  AsciiReader lines = in;
  std::int64_t count = 0;
  while (count < e.count && lines.NextLine()) ++count;
  if (count < e.count) {
    lines.Fail("file ends after " + std::to_string(count) + " of " + std::to_string(e.count) + " " + Plural(e) +
               " (" + declared + ")");
  }
  in.Fail(declared + " (each needs at least " + std::to_string(min_bytes) + ")");
}

void ReadAsciiVertices(AsciiReader* in, const Element& e, const std::vector<Slot>& slots, PointCloud* cloud) {
  const Eigen::Index n = e.count;
  for (Eigen::Index i = 0; i < n; ++i) {
    if (!in->NextLine()) {
      in->Fail("file ends after " + std::to_string(i) + " of " + std::to_string(n) + " vertices");
    }
    for (const Slot& s : slots) {
      AsciiReader::Status status;
      if (s.is_list) {
        std::int64_t count = 0;
        status = in->Read(&count);
        if (status == AsciiReader::Status::kOk && count < 0) in->Fail("negative list length in " + PropertyOf(*s.property, e, i));
        for (std::int64_t k = 0; k < count && status == AsciiReader::Status::kOk; ++k) status = in->SkipToken();
      } else {
        double v = 0;
        status = in->ReadValue(s.type, &v);
        Apply(s, i, v);
      }
      if (status != AsciiReader::Status::kOk) [[unlikely]] {
        in->FailRead(status, PropertyOf(*s.property, e, i));
      }
    }
    if (!in->AtLineEnd()) {
      in->Fail("vertex " + std::to_string(i) + " has more values than the " + std::to_string(slots.size()) +
               " properties the header declares");
    }
    const double* x = cloud->positions.data() + 3 * i;
    if (!std::isfinite(x[0]) || !std::isfinite(x[1]) || !std::isfinite(x[2])) {
      in->Fail("vertex " + std::to_string(i) + " has a non-finite coordinate (NaN or Inf)");
    }
  }
}

void ReadAsciiFaces(AsciiReader* in, const Element& e, int index_property, std::int64_t num_vertices,
                    FaceSink* sink) {
  std::vector<std::int64_t> polygon;
  for (std::int64_t f = 0; f < e.count; ++f) {
    if (!in->NextLine()) {
      in->Fail("file ends after " + std::to_string(f) + " of " + std::to_string(e.count) + " faces");
    }
    for (std::size_t k = 0; k < e.properties.size(); ++k) {
      const Property& p = e.properties[k];
      AsciiReader::Status status = AsciiReader::Status::kOk;
      if (static_cast<int>(k) == index_property) {
        std::int64_t count = 0;
        status = in->Read(&count);
        if (status != AsciiReader::Status::kOk) in->FailRead(status, "the vertex count of face " + std::to_string(f));
        if (count < 3) {
          in->Fail("face " + std::to_string(f) + " has " + std::to_string(count) + " vertices (at least 3 needed)");
        }
        polygon.clear();
        for (std::int64_t j = 0; j < count; ++j) {
          std::int64_t v = 0;
          status = in->Read(&v);
          if (status != AsciiReader::Status::kOk) {
            in->FailRead(status, "index " + std::to_string(j) + " of face " + std::to_string(f) + " (it lists " +
                                     std::to_string(count) + ")");
          }
          if (v < 0 || v >= num_vertices) {
            in->Fail("face " + std::to_string(f) + " refers to vertex " + std::to_string(v) + " but there are " +
                     std::to_string(num_vertices) + " vertices");
          }
          polygon.push_back(v);
        }
        sink->AddPolygon(polygon.data(), count);
      } else if (p.is_list) {
        std::int64_t count = 0;
        status = in->Read(&count);
        if (status == AsciiReader::Status::kOk && count < 0) in->Fail("negative list length in " + PropertyOf(p, e, f));
        for (std::int64_t j = 0; j < count && status == AsciiReader::Status::kOk; ++j) status = in->SkipToken();
      } else {
        status = in->SkipToken();
      }
      if (status != AsciiReader::Status::kOk) in->FailRead(status, PropertyOf(p, e, f));
    }
    if (!in->AtLineEnd()) {
      in->Fail("face " + std::to_string(f) + " has more values than its properties declare");
    }
  }
}

void SkipAsciiElement(AsciiReader* in, const Element& e) {
  if (e.properties.empty()) return;  // an item without properties has nothing on its line
  for (std::int64_t i = 0; i < e.count; ++i) {
    if (!in->NextLine()) {
      in->Fail("file ends after " + std::to_string(i) + " of " + std::to_string(e.count) + " " + Plural(e));
    }
  }
}

// ------------------------------------------------------------------------------------------------
// Binary data.

class BinaryReader {
 public:
  BinaryReader(std::string_view data, bool swap, const std::string& name)
      : p_(data.data()), end_(data.data() + data.size()), swap_(swap), name_(name) {}

  std::size_t left() const { return static_cast<std::size_t>(end_ - p_); }
  const char* position() const { return p_; }
  void Advance(std::size_t bytes) { p_ += bytes; }
  void set_position(const char* p) { p_ = p; }
  const char* end() const { return end_; }
  bool swap() const { return swap_; }
  const std::string& name() const { return name_; }

  [[noreturn]] void FailEnds(const Element& e, std::int64_t done) const {
    ThrowBadInput(name_, "file ends after " + std::to_string(done) + " of " + std::to_string(e.count) + " " +
                             Plural(e) + " (the data is truncated or the header is wrong)");
  }

  /// Reads one list length at the current position (after checking it is there), advancing past it.
  /// Returns -1 if the data ends.
  std::int64_t ReadCount(Type t, const Element& e, const Property& p, std::int64_t item) {
    const std::size_t size = SizeOf(t);
    if (left() < size) return -1;
    const double count = LoadAsDouble(p_, t, swap_);
    if (count < 0) {
      ThrowBadInput(name_, "negative list length " + std::to_string(static_cast<std::int64_t>(count)) + " in " +
                               PropertyOf(p, e, item));
    }
    p_ += size;
    return static_cast<std::int64_t>(count);
  }

  /// Skips a list of `count` items of type t; false if the data ends first.
  bool SkipItems(std::int64_t count, Type t) {
    if (static_cast<std::uint64_t>(count) > left() / SizeOf(t)) return false;
    p_ += static_cast<std::size_t>(count) * SizeOf(t);
    return true;
  }

 private:
  const char* p_;
  const char* end_;
  bool swap_;
  const std::string& name_;
};

/// Consecutive wanted properties copied together: `width` (1 or 3) values of one type at consecutive
/// offsets going to consecutive columns of one destination row (x y z, nx ny nz, red green blue).
struct Run {
  const Slot* slot;
  int width;
};

std::vector<Run> GroupRuns(const std::vector<Slot>& slots) {
  std::vector<Run> runs;
  for (std::size_t i = 0; i < slots.size(); ++i) {
    const Slot& a = slots[i];
    if (a.kind == Slot::Kind::kIgnore) continue;
    if (i + 2 < slots.size() && a.stride == 3) {
      const Slot& b = slots[i + 1];
      const Slot& c = slots[i + 2];
      const std::size_t size = SizeOf(a.type);
      const bool same = b.kind == a.kind && c.kind == a.kind && b.type == a.type && c.type == a.type &&
                        b.offset == a.offset + size && c.offset == a.offset + 2 * size;
      const bool adjacent = a.kind == Slot::Kind::kValue ? (b.values == a.values + 1 && c.values == a.values + 2)
                                                         : (b.colors == a.colors + 1 && c.colors == a.colors + 2);
      if (same && adjacent) {
        runs.push_back({&a, 3});
        i += 2;
        continue;
      }
    }
    runs.push_back({&a, 1});
  }
  return runs;
}

template <typename Out, typename T>
inline Out Convert(T v) {
  if constexpr (std::is_same_v<Out, double>) {
    return static_cast<double>(v);
  } else {
    return ColorFromValue(static_cast<double>(v), std::is_integral_v<T>);
  }
}

/// Copies `n` records' run of kWidth values of type T into dst (stride dst_stride per record).
template <typename T, bool kSwap, int kWidth, typename Out>
void CopyRun(const char* src, std::size_t stride, std::size_t n, Out* dst, std::ptrdiff_t dst_stride) {
  for (std::size_t i = 0; i < n; ++i, src += stride, dst += dst_stride) {
    for (int k = 0; k < kWidth; ++k) dst[k] = Convert<Out>(Load<T, kSwap>(src + k * sizeof(T)));
  }
}

template <typename T, bool kSwap, typename Out>
void CopyRun(const Run& run, const char* src, std::size_t stride, std::size_t n, Out* dst) {
  run.width == 3 ? CopyRun<T, kSwap, 3>(src, stride, n, dst, run.slot->stride)
                 : CopyRun<T, kSwap, 1>(src, stride, n, dst, run.slot->stride);
}

/// Copies one run of the fixed-size records [first, first + n), which start at `records`.
void CopyRun(const Run& run, const char* records, std::size_t record_size, std::size_t first, std::size_t n,
             bool swap) {
  const Slot& s = *run.slot;
  const char* src = records + s.offset;
  const std::ptrdiff_t at = static_cast<std::ptrdiff_t>(first) * s.stride;
  WithType(s.type, [&](auto tag) {
    using T = typename decltype(tag)::type;
    if (s.kind == Slot::Kind::kValue) {
      swap ? CopyRun<T, true>(run, src, record_size, n, s.values + at)
           : CopyRun<T, false>(run, src, record_size, n, s.values + at);
    } else {
      swap ? CopyRun<T, true>(run, src, record_size, n, s.colors + at)
           : CopyRun<T, false>(run, src, record_size, n, s.colors + at);
    }
  });
}

/// True if none of v[0..n) is NaN or Inf (a branch-free loop that vectorises).
bool AllFinite(const double* v, std::size_t n) {
  // The exponent bits plus one carry into the sign bit exactly when they are all ones (NaN or Inf).
  constexpr std::uint64_t kExponent = 0x7ff0000000000000ull, kExponentOne = 0x0010000000000000ull;
  std::uint64_t carry = 0;
  for (std::size_t i = 0; i < n; ++i) carry |= (std::bit_cast<std::uint64_t>(v[i]) & kExponent) + kExponentOne;
  return (carry >> 63) == 0;
}

[[noreturn]] void FailNonFinite(const std::string& name, Eigen::Index vertex) {
  ThrowBadInput(name, "vertex " + std::to_string(vertex) + " has a non-finite coordinate (NaN or Inf)");
}

void ReadBinaryVertices(BinaryReader* in, const Element& e, const std::vector<Slot>& slots, PointCloud* cloud) {
  const std::size_t n = static_cast<std::size_t>(e.count);
  if (n == 0) return;
  if (!e.HasList()) {
    // Fixed-size records: a block of records (that stays in cache) at a time, run by run.
    const std::size_t record_size = e.MinBinarySize();
    const std::size_t available = in->left() / record_size;
    if (available < n) in->FailEnds(e, static_cast<std::int64_t>(available));
    const std::vector<Run> runs = GroupRuns(slots);
    constexpr std::size_t kBlock = 1024;
    for (std::size_t first = 0; first < n; first += kBlock) {
      const std::size_t m = std::min(kBlock, n - first);
      const char* records = in->position() + first * record_size;
      for (const Run& run : runs) CopyRun(run, records, record_size, first, m, in->swap());
      if (!AllFinite(cloud->positions.data() + 3 * first, 3 * m)) [[unlikely]] {
        for (std::size_t i = first;; ++i) {
          if (!cloud->positions.row(static_cast<Eigen::Index>(i)).allFinite()) FailNonFinite(in->name(), static_cast<Eigen::Index>(i));
        }
      }
    }
    in->Advance(n * record_size);
  } else {
    // Records with lists: walk each one.
    for (std::size_t i = 0; i < n; ++i) {
      for (const Slot& s : slots) {
        if (s.is_list) {
          const std::int64_t count = in->ReadCount(s.count_type, e, *s.property, static_cast<std::int64_t>(i));
          if (count < 0 || !in->SkipItems(count, s.type)) in->FailEnds(e, static_cast<std::int64_t>(i));
          continue;
        }
        const std::size_t size = SizeOf(s.type);
        if (in->left() < size) in->FailEnds(e, static_cast<std::int64_t>(i));
        Apply(s, static_cast<Eigen::Index>(i), LoadAsDouble(in->position(), s.type, in->swap()));
        in->Advance(size);
      }
    }
    if (!cloud->positions.allFinite()) {
      for (Eigen::Index i = 0;; ++i) {
        if (!cloud->positions.row(i).allFinite()) FailNonFinite(in->name(), i);
      }
    }
  }
}

[[noreturn]] void FailIndex(const std::string& name, std::int64_t face, std::int64_t vertex,
                            std::int64_t num_vertices) {
  ThrowBadInput(name, "face " + std::to_string(face) + " refers to vertex " + std::to_string(vertex) +
                          " but there are " + std::to_string(num_vertices) + " vertices");
}

[[noreturn]] void FailFaceSize(const std::string& name, std::int64_t face, std::int64_t count) {
  ThrowBadInput(name,
                "face " + std::to_string(face) + " has " + std::to_string(count) + " vertices (at least 3 needed)");
}

/// Faces whose only property is `list uchar int|uint vertex_indices`, triangles in one step.
template <typename Index, bool kSwap>
void ReadBinaryFacesFast(BinaryReader* in, const Element& e, std::int64_t num_vertices, FaceSink* sink) {
  const char* p = in->position();
  const char* const end = in->end();
  const auto limit = static_cast<std::uint64_t>(num_vertices);
  std::vector<std::int32_t> polygon;
  for (std::int64_t f = 0; f < e.count; ++f) {
    if (p == end) in->FailEnds(e, f);
    const auto count = static_cast<std::uint8_t>(*p);
    if (count == 3 && end - p >= 13) [[likely]] {
      const auto a = static_cast<std::int64_t>(Load<Index, kSwap>(p + 1));
      const auto b = static_cast<std::int64_t>(Load<Index, kSwap>(p + 5));
      const auto c = static_cast<std::int64_t>(Load<Index, kSwap>(p + 9));
      if (static_cast<std::uint64_t>(a) >= limit || static_cast<std::uint64_t>(b) >= limit ||
          static_cast<std::uint64_t>(c) >= limit) [[unlikely]] {
        const std::int64_t bad = static_cast<std::uint64_t>(a) >= limit   ? a
                                 : static_cast<std::uint64_t>(b) >= limit ? b
                                                                          : c;
        FailIndex(in->name(), f, bad, num_vertices);
      }
      sink->Add(static_cast<std::int32_t>(a), static_cast<std::int32_t>(b), static_cast<std::int32_t>(c));
      p += 13;
      continue;
    }
    if (count < 3) FailFaceSize(in->name(), f, count);
    if (static_cast<std::size_t>(end - p - 1) < 4u * count) in->FailEnds(e, f);
    polygon.resize(count);
    for (int j = 0; j < count; ++j) {
      const auto v = static_cast<std::int64_t>(Load<Index, kSwap>(p + 1 + 4 * j));
      if (static_cast<std::uint64_t>(v) >= limit) FailIndex(in->name(), f, v, num_vertices);
      polygon[j] = static_cast<std::int32_t>(v);
    }
    sink->AddPolygon(polygon.data(), count);
    p += 1 + 4 * count;
  }
  in->set_position(p);
}

void ReadBinaryFaces(BinaryReader* in, const Element& e, int index_property, std::int64_t num_vertices,
                     FaceSink* sink) {
  const Property& index = e.properties[index_property];
  if (e.properties.size() == 1 && index.count_type == Type::kUint8 &&
      (index.type == Type::kInt32 || index.type == Type::kUint32)) {
    const bool is_signed = index.type == Type::kInt32;
    if (in->swap()) {
      is_signed ? ReadBinaryFacesFast<std::int32_t, true>(in, e, num_vertices, sink)
                : ReadBinaryFacesFast<std::uint32_t, true>(in, e, num_vertices, sink);
    } else {
      is_signed ? ReadBinaryFacesFast<std::int32_t, false>(in, e, num_vertices, sink)
                : ReadBinaryFacesFast<std::uint32_t, false>(in, e, num_vertices, sink);
    }
    return;
  }
  std::vector<std::int32_t> polygon;
  for (std::int64_t f = 0; f < e.count; ++f) {
    for (std::size_t k = 0; k < e.properties.size(); ++k) {
      const Property& p = e.properties[k];
      if (!p.is_list) {
        if (in->left() < SizeOf(p.type)) in->FailEnds(e, f);
        in->Advance(SizeOf(p.type));
        continue;
      }
      const std::int64_t count = in->ReadCount(p.count_type, e, p, f);
      if (count < 0) in->FailEnds(e, f);
      if (static_cast<int>(k) != index_property) {
        if (!in->SkipItems(count, p.type)) in->FailEnds(e, f);
        continue;
      }
      if (count < 3) FailFaceSize(in->name(), f, count);
      const std::size_t size = SizeOf(p.type);
      if (static_cast<std::uint64_t>(count) > in->left() / size) in->FailEnds(e, f);
      polygon.resize(static_cast<std::size_t>(count));
      for (std::int64_t j = 0; j < count; ++j) {
        const double v = LoadAsDouble(in->position(), p.type, in->swap());
        if (v < 0 || v >= static_cast<double>(num_vertices)) {
          FailIndex(in->name(), f, static_cast<std::int64_t>(v), num_vertices);
        }
        polygon[j] = static_cast<std::int32_t>(v);
        in->Advance(size);
      }
      sink->AddPolygon(polygon.data(), count);
    }
  }
}

void SkipBinaryElement(BinaryReader* in, const Element& e) {
  if (!e.HasList()) {
    const std::size_t size = e.MinBinarySize();
    if (size == 0) return;
    const std::size_t available = in->left() / size;
    if (static_cast<std::uint64_t>(e.count) > available) in->FailEnds(e, static_cast<std::int64_t>(available));
    in->Advance(static_cast<std::size_t>(e.count) * size);
    return;
  }
  for (std::int64_t i = 0; i < e.count; ++i) {
    for (const Property& p : e.properties) {
      if (p.is_list) {
        const std::int64_t count = in->ReadCount(p.count_type, e, p, i);
        if (count < 0 || !in->SkipItems(count, p.type)) in->FailEnds(e, i);
      } else {
        if (in->left() < SizeOf(p.type)) in->FailEnds(e, i);
        in->Advance(SizeOf(p.type));
      }
    }
  }
}

/// Checks the vertices can fit in the bytes left before they are allocated.
void CheckBinaryFits(const BinaryReader& in, const Element& e) {
  const std::size_t min_size = e.MinBinarySize();
  if (min_size == 0) return;  // no properties: MapVertexProperties says x y z are missing
  const std::size_t available = in.left() / min_size;
  if (static_cast<std::uint64_t>(e.count) <= available) return;
  if (!e.HasList()) in.FailEnds(e, static_cast<std::int64_t>(available));
  ThrowBadInput(in.name(), "the header declares " + std::to_string(e.count) + " " + Plural(e) +
                               " but only " + std::to_string(in.left()) + " bytes of data remain (each needs at least " +
                               std::to_string(min_size) + ")");
}

// ------------------------------------------------------------------------------------------------
// Writing.

std::string ScalarPropertyName(const std::string& scalar) {
  std::string out = scalar.empty() ? std::string("scalar") : scalar;
  for (char& c : out) {
    if (IsBlank(c) || c == '\n') c = '_';
  }
  static const char* const kReserved[] = {"x",   "y",     "z",    "nx",    "ny",           "nz",
                                          "red", "green", "blue", "alpha", "vertex_indices"};
  for (const char* reserved : kReserved) {
    if (out == reserved) ThrowUsage("cannot write a scalar named '" + out + "' to PLY: the name is reserved");
  }
  return out;
}

/// Appends the shortest text that reads back as exactly v.
template <typename T>
inline void AppendNumber(std::string* out, T v) {
  char buffer[64];
  const auto result = std::to_chars(buffer, buffer + sizeof(buffer), v);
  out->append(buffer, result.ptr);
}

}  // namespace

TriangleMesh ParsePly(std::string_view bytes, const std::string& name, FileSummary* summary) {
  if (summary != nullptr) *summary = FileSummary{};
  const Header header = ParseHeader(bytes, name, summary);

  // Which elements hold the vertices and the faces.
  const Element* vertex = nullptr;
  const Element* face = nullptr;
  int index_property = -1;
  for (const Element& e : header.elements) {
    if (e.name == "vertex") vertex = &e;
    if (e.name == "face") face = &e;
  }
  if (vertex == nullptr) ThrowBadInput(name, "the PLY header declares no vertex element");
  if (vertex->count > std::numeric_limits<std::int32_t>::max()) {
    ThrowBadInput(name, "too many vertices (" + std::to_string(vertex->count) + ")", vertex->header_line);
  }
  if (face != nullptr) {
    index_property = face->FindProperty("vertex_indices");
    if (index_property < 0) index_property = face->FindProperty("vertex_index");
    if (index_property < 0 || !face->properties[index_property].is_list) {
      ThrowBadInput(name, "the face element has no list property 'vertex_indices'", face->header_line);
    }
    if (!IsInteger(face->properties[index_property].type)) {
      ThrowBadInput(name, "the face indices must have an integer type", face->header_line);
    }
  }

  TriangleMesh mesh;
  Faces3 faces;
  const std::string_view data = bytes.substr(header.data_offset);
  if (header.encoding == Encoding::kAscii) {
    AsciiReader in(data, header.line_count, name);
    for (const Element& e : header.elements) {
      if (&e == vertex) {
        CheckAsciiFits(in, e);
        const std::vector<Slot> slots = MapVertexProperties(e, name, &mesh.vertices);
        ReadAsciiVertices(&in, e, slots, &mesh.vertices);
      } else if (&e == face) {
        // A face line takes at least 7 bytes ("3 0 1 2"); a short file fails while reading.
        FaceSink sink(std::min<std::int64_t>(e.count, static_cast<std::int64_t>(in.bytes_left() / 8)));
        ReadAsciiFaces(&in, e, index_property, vertex->count, &sink);
        faces = sink.Finish();
      } else {
        SkipAsciiElement(&in, e);
      }
    }
    in.ExpectEnd();
  } else {
    const bool file_is_big_endian = header.encoding == Encoding::kBinaryBigEndian;
    const bool swap = file_is_big_endian != (std::endian::native == std::endian::big);
    BinaryReader in(data, swap, name);
    for (const Element& e : header.elements) {
      if (&e == vertex) {
        CheckBinaryFits(in, e);
        const std::vector<Slot> slots = MapVertexProperties(e, name, &mesh.vertices);
        ReadBinaryVertices(&in, e, slots, &mesh.vertices);
      } else if (&e == face) {
        // Reserve no more faces than the bytes left can hold; a short file fails while reading.
        const std::size_t min_size = e.MinBinarySize() + 3 * SizeOf(e.properties[index_property].type);
        FaceSink sink(std::min<std::int64_t>(e.count, static_cast<std::int64_t>(in.left() / min_size)));
        ReadBinaryFaces(&in, e, index_property, vertex->count, &sink);
        faces = sink.Finish();
      } else {
        SkipBinaryElement(&in, e);
      }
    }
    // Bytes after the last element are allowed (some writers pad files).
  }
  if (faces.rows() == 0) faces.resize(0, 3);
  mesh.faces = std::move(faces);
  return mesh;
}

void WritePly(std::ostream& out, const TriangleMesh& mesh, const WriteOptions& options) {
  const PointCloud& cloud = mesh.vertices;
  const Eigen::Index n = cloud.size();
  if (cloud.has_normals() && cloud.normals.rows() != n) ThrowUsage("PLY writer: normals and positions differ in count");
  if (cloud.has_colors() && cloud.colors.rows() != n) ThrowUsage("PLY writer: colours and positions differ in count");
  std::vector<std::string> scalar_names;
  std::vector<const double*> scalar_values;
  for (const auto& [scalar_name, values] : cloud.scalars) {
    if (values.size() != n) ThrowUsage("PLY writer: scalar '" + scalar_name + "' and positions differ in count");
    scalar_names.push_back(ScalarPropertyName(scalar_name));
    scalar_values.push_back(values.data());
  }
  // Far-from-origin data keeps sub-millimetre precision as double.
  const bool wide = n > 0 && cloud.positions.cwiseAbs().maxCoeff() > 1e5;
  const bool normals = cloud.has_normals(), colors = cloud.has_colors();
  const Eigen::Index num_faces = mesh.num_faces();

  // Header.
  std::string header = "ply\nformat ";
  header += options.binary ? "binary_little_endian 1.0\n" : "ascii 1.0\n";
  std::size_t start = 0;
  while (start < options.comment.size()) {
    std::size_t stop = options.comment.find('\n', start);
    if (stop == std::string::npos) stop = options.comment.size();
    std::string_view text(options.comment.data() + start, stop - start);
    if (!text.empty() && text.back() == '\r') text.remove_suffix(1);
    header += "comment " + std::string(text) + "\n";
    start = stop + 1;
  }
  header += "comment pectus units mm\n";
  header += "element vertex " + std::to_string(n) + "\n";
  const char* position_type = wide ? "double" : "float";
  for (const char* axis : {"x", "y", "z"}) header += std::string("property ") + position_type + " " + axis + "\n";
  if (normals) header += "property float nx\nproperty float ny\nproperty float nz\n";
  if (colors) header += "property uchar red\nproperty uchar green\nproperty uchar blue\n";
  for (const std::string& s : scalar_names) header += "property float " + s + "\n";
  if (num_faces > 0) header += "element face " + std::to_string(num_faces) + "\nproperty list uchar int vertex_indices\n";
  header += "end_header\n";
  out.write(header.data(), static_cast<std::streamsize>(header.size()));

  const double* pos = cloud.positions.data();
  const double* nrm = normals ? cloud.normals.data() : nullptr;
  const std::uint8_t* rgb = colors ? cloud.colors.data() : nullptr;
  const std::int32_t* tri = mesh.faces.data();
  if (options.binary) {
    const std::size_t record_size =
        (wide ? 24 : 12) + (normals ? 12 : 0) + (colors ? 3 : 0) + 4 * scalar_values.size();
    const std::size_t vertex_bytes = record_size * static_cast<std::size_t>(n);
    const std::size_t face_bytes = 13 * static_cast<std::size_t>(num_faces);
    auto buffer = std::make_unique_for_overwrite<char[]>(std::max(vertex_bytes, face_bytes) + 1);
    char* r = buffer.get();
    for (Eigen::Index i = 0; i < n; ++i) {
      for (int k = 0; k < 3; ++k, r += wide ? 8 : 4) {
        wide ? StoreLittleEndian(r, pos[3 * i + k]) : StoreLittleEndian(r, static_cast<float>(pos[3 * i + k]));
      }
      if (normals) {
        for (int k = 0; k < 3; ++k, r += 4) StoreLittleEndian(r, static_cast<float>(nrm[3 * i + k]));
      }
      if (colors) {
        std::memcpy(r, rgb + 3 * i, 3);
        r += 3;
      }
      for (const double* values : scalar_values) {
        StoreLittleEndian(r, static_cast<float>(values[i]));
        r += 4;
      }
    }
    out.write(buffer.get(), static_cast<std::streamsize>(vertex_bytes));
    r = buffer.get();
    for (Eigen::Index f = 0; f < num_faces; ++f, r += 13) {
      r[0] = 3;
      for (int k = 0; k < 3; ++k) StoreLittleEndian(r + 1 + 4 * k, tri[3 * f + k]);
    }
    out.write(buffer.get(), static_cast<std::streamsize>(face_bytes));
  } else {
    std::string text;
    constexpr std::size_t kFlush = 1 << 20;
    text.reserve(kFlush + 4096);
    auto flush = [&](bool force) {
      if (text.size() >= kFlush || force) {
        out.write(text.data(), static_cast<std::streamsize>(text.size()));
        text.clear();
      }
    };
    for (Eigen::Index i = 0; i < n; ++i) {
      for (int k = 0; k < 3; ++k) {
        if (k > 0) text += ' ';
        wide ? AppendNumber(&text, pos[3 * i + k]) : AppendNumber(&text, static_cast<float>(pos[3 * i + k]));
      }
      for (int k = 0; normals && k < 3; ++k) {
        text += ' ';
        AppendNumber(&text, static_cast<float>(nrm[3 * i + k]));
      }
      for (int k = 0; colors && k < 3; ++k) {
        text += ' ';
        AppendNumber(&text, static_cast<int>(rgb[3 * i + k]));
      }
      for (const double* values : scalar_values) {
        text += ' ';
        AppendNumber(&text, static_cast<float>(values[i]));
      }
      text += '\n';
      flush(false);
    }
    for (Eigen::Index f = 0; f < num_faces; ++f) {
      text += '3';
      for (int k = 0; k < 3; ++k) {
        text += ' ';
        AppendNumber(&text, tri[3 * f + k]);
      }
      text += '\n';
      flush(false);
    }
    flush(true);
  }
  if (!out) ThrowFailure("could not write the PLY data");
}

}  // namespace pectus
