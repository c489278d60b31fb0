// pectus: PCD reader (PCL's Point Cloud Data: ascii, binary, binary_compressed). The header is read and
// checked by pcd_header.cc; this file reads the data into columns, one per field, and the columns into a
// point cloud. LZF blocks are expanded by liblzf.
#include <lzf.h>

#include <charconv>
#include <cmath>
#include <cstring>
#include <limits>

#include "shape/core/error.h"
#include "shape/core/log.h"
#include "shape/io/format_parsers.h"
#include "shape/io/pcd_format.h"
#include "shape/io/text_scan.h"

namespace pectus {
namespace {

template <typename T>
double Load(const std::uint8_t* p) {
  T v;
  std::memcpy(&v, p, sizeof v);
  return static_cast<double>(v);
}

// The value of one element at `p`, as a double.
double LoadAsDouble(pcd::Type type, const std::uint8_t* p) {
  switch (type) {
    case pcd::Type::kInt8: return Load<std::int8_t>(p);
    case pcd::Type::kUint8: return Load<std::uint8_t>(p);
    case pcd::Type::kInt16: return Load<std::int16_t>(p);
    case pcd::Type::kUint16: return Load<std::uint16_t>(p);
    case pcd::Type::kInt32: return Load<std::int32_t>(p);
    case pcd::Type::kUint32: return Load<std::uint32_t>(p);
    case pcd::Type::kInt64: return Load<std::int64_t>(p);
    case pcd::Type::kUint64: return Load<std::uint64_t>(p);
    case pcd::Type::kFloat32: return Load<float>(p);
    case pcd::Type::kFloat64: return Load<double>(p);
  }
  return std::nan("");
}

// A field's values: point i's first element at base + i * stride.
struct Column {
  const pcd::Field* field = nullptr;
  const std::uint8_t* base = nullptr;
  std::size_t stride = 0;

  double Value(std::size_t i) const { return LoadAsDouble(field->type, base + i * stride); }
  const std::uint8_t* At(std::size_t i) const { return base + i * stride; }
};

// Parses `token` as a T into `out`; false if it is not entirely a T in range.
template <typename T>
bool ParseAs(std::string_view token, std::uint8_t* out) {
  if (!token.empty() && token.front() == '+') token.remove_prefix(1);
  T v{};
  const auto [ptr, ec] = std::from_chars(token.data(), token.data() + token.size(), v);
  if (ec != std::errc() || ptr != token.data() + token.size() || token.empty()) return false;
  std::memcpy(out, &v, sizeof v);
  return true;
}

bool ParseElement(pcd::Type type, std::string_view token, std::uint8_t* out) {
  switch (type) {
    case pcd::Type::kInt8: return ParseAs<std::int8_t>(token, out);
    case pcd::Type::kUint8: return ParseAs<std::uint8_t>(token, out);
    case pcd::Type::kInt16: return ParseAs<std::int16_t>(token, out);
    case pcd::Type::kUint16: return ParseAs<std::uint16_t>(token, out);
    case pcd::Type::kInt32: return ParseAs<std::int32_t>(token, out);
    case pcd::Type::kUint32: return ParseAs<std::uint32_t>(token, out);
    case pcd::Type::kInt64: return ParseAs<std::int64_t>(token, out);
    case pcd::Type::kUint64: return ParseAs<std::uint64_t>(token, out);
    case pcd::Type::kFloat32: return ParseAs<float>(token, out);
    case pcd::Type::kFloat64: return ParseAs<double>(token, out);
  }
  return false;
}

// ascii: one point a line (blank lines skipped), into binary points of header.point_bytes each. Lines
// after the last point are not read, as PCL does not read them.
std::vector<std::uint8_t> ReadAscii(std::string_view bytes, const pcd::Header& header,
                                    const std::string& name) {
  std::vector<std::uint8_t> data(header.points * header.point_bytes);
  text::LineReader lines(bytes.substr(header.data_offset));
  std::string_view line;
  std::uint64_t i = 0;
  while (i < header.points && lines.Next(&line)) {
    const std::int64_t number = header.data_line + lines.number() - 1;
    std::string_view rest = line;
    std::string_view token = text::NextToken(&rest);
    if (token.empty()) continue;
    std::uint8_t* point = data.data() + i * header.point_bytes;
    std::uint64_t values = 0;
    for (const pcd::Field& f : header.fields) {
      for (std::uint64_t c = 0; c < f.count; ++c, ++values, token = text::NextToken(&rest)) {
        if (token.empty()) {
          ThrowBadInput(name,
                        "PCD point " + std::to_string(i) + " has " + std::to_string(values) +
                            " values; its fields need " + std::to_string(header.values_per_point),
                        number);
        }
        std::uint8_t* out = point + f.offset + c * f.size;
        // PCL writes a float "rgb" as the integer of its bits (several opaque colours are NaN as floats).
        const bool packed = f.name == "rgb" && f.type == pcd::Type::kFloat32;
        if ((packed && ParseAs<std::uint32_t>(token, out)) || ParseElement(f.type, token, out)) continue;
        ThrowBadInput(name,
                      "PCD point " + std::to_string(i) + ": " + text::Quoted(token) + " is not a " +
                          pcd::TypeName(f.type) + " (field '" + f.name + "')",
                      number);
      }
    }
    if (!token.empty()) {
      ThrowBadInput(name,
                    "PCD point " + std::to_string(i) + " has more than the " +
                        std::to_string(header.values_per_point) + " values its fields need",
                    number);
    }
    ++i;
  }
  if (i < header.points) {
    ThrowBadInput(name, "truncated PCD file: the header declares " + std::to_string(header.points) +
                            " points but the data holds " + std::to_string(i));
  }
  return data;
}

// The fields' columns over the data, read (ascii) or expanded (binary_compressed) into `storage` where
// the file's bytes cannot be read in place.
std::vector<Column> ReadColumns(std::string_view bytes, const pcd::Header& header, const std::string& name,
                                std::vector<std::uint8_t>* storage) {
  std::vector<Column> columns;
  if (header.points == 0) {
    // Nothing to read (and no offsets to add to an empty buffer's null pointer: found by fuzzing).
    for (const pcd::Field& f : header.fields) columns.push_back(Column{&f, nullptr, 0});
    return columns;
  }
  const auto* file = reinterpret_cast<const std::uint8_t*>(bytes.data());
  if (header.encoding == pcd::Encoding::kBinaryCompressed) {
    // Field after field, without the padding; the sizes were checked against the header and the file.
    storage->resize(header.uncompressed_bytes);
    if (header.uncompressed_bytes > 0 &&
        lzf_decompress(file + header.data_offset + 8, header.compressed_bytes, storage->data(),
                       header.uncompressed_bytes) != header.uncompressed_bytes) {
      ThrowBadInput(name, "PCD compressed block is corrupt: it does not expand to the " +
                              std::to_string(header.uncompressed_bytes) + " bytes its header gives");
    }
    std::size_t start = 0;
    for (const pcd::Field& f : header.fields) {
      columns.push_back(Column{&f, storage->data() + start, f.bytes()});
      if (!f.is_padding()) start += header.points * f.bytes();
    }
    return columns;
  }
  const std::uint8_t* points = file + header.data_offset;
  if (header.encoding == pcd::Encoding::kAscii) {
    *storage = ReadAscii(bytes, header, name);
    points = storage->data();
  }
  for (const pcd::Field& f : header.fields)
    columns.push_back(Column{&f, points + f.offset, header.point_bytes});
  return columns;
}

const Column* FindColumn(const std::vector<Column>& columns, const std::string& name) {
  for (const Column& c : columns) {
    if (c.field->name == name) return &c;
  }
  return nullptr;
}

}  // namespace

TriangleMesh ParsePcd(std::string_view bytes, const std::string& name, FileSummary* summary) {
  if (summary) *summary = FileSummary{};
  const pcd::Header header = pcd::ParseHeader(bytes, name);
  std::vector<std::uint8_t> storage;
  const std::vector<Column> columns = ReadColumns(bytes, header, name, &storage);
  const auto n = static_cast<std::size_t>(header.points);

  const Column* xyz[3] = {FindColumn(columns, "x"), FindColumn(columns, "y"), FindColumn(columns, "z")};
  if (!xyz[0] || !xyz[1] || !xyz[2]) ThrowBadInput(name, "PCD file has no x, y, z fields");
  const Column* normal[3] = {FindColumn(columns, "normal_x"), FindColumn(columns, "normal_y"),
                             FindColumn(columns, "normal_z")};
  const bool has_normals = normal[0] && normal[1] && normal[2];
  const Column* rgb = FindColumn(columns, "rgb");
  if (!rgb) rgb = FindColumn(columns, "rgba");
  if (rgb && rgb->field->size != 4) rgb = nullptr;
  std::vector<const Column*> scalars;
  for (const Column& c : columns) {
    const bool known = &c == xyz[0] || &c == xyz[1] || &c == xyz[2] || &c == rgb ||
                       (has_normals && (&c == normal[0] || &c == normal[1] || &c == normal[2]));
    // Padding ("_") and multi-element fields (descriptors such as fpfh[33]) are not per-point scalars.
    if (!known && !c.field->is_padding() && c.field->count == 1) scalars.push_back(&c);
  }

  // Organized clouds mark missing returns with NaN positions: those points are left out.
  std::vector<std::size_t> keep;
  keep.reserve(n);
  for (std::size_t i = 0; i < n; ++i) {
    bool finite = true;
    for (const Column* c : xyz) finite = finite && std::isfinite(c->Value(i));
    if (finite) keep.push_back(i);
  }
  if (keep.size() < n) {
    Warn(name + ": " + std::to_string(n - keep.size()) + " of " + std::to_string(n) +
         " points have no valid position (NaN) and were left out");
  }

  const auto m = static_cast<Eigen::Index>(keep.size());
  TriangleMesh mesh;
  PointCloud& out = mesh.vertices;
  out.positions.resize(m, 3);
  if (has_normals) out.normals.resize(m, 3);
  if (rgb) out.colors.resize(m, 3);
  for (const Column* c : scalars) out.scalars[c->field->name].resize(m);
  for (Eigen::Index j = 0; j < m; ++j) {
    const std::size_t i = keep[static_cast<std::size_t>(j)];
    for (int k = 0; k < 3; ++k) {
      out.positions(j, k) = xyz[k]->Value(i);
      if (has_normals) out.normals(j, k) = normal[k]->Value(i);
    }
    if (rgb) {
      // Packed 0x(AA)RRGGBB in a float or uint32.
      std::uint32_t packed;
      std::memcpy(&packed, rgb->At(i), 4);
      out.colors.row(j) << static_cast<std::uint8_t>((packed >> 16) & 0xFF),
          static_cast<std::uint8_t>((packed >> 8) & 0xFF), static_cast<std::uint8_t>(packed & 0xFF);
    }
    for (const Column* c : scalars) out.scalars[c->field->name][j] = c->Value(i);
  }
  mesh.faces.resize(0, 3);

  if (summary) {
    summary->format = "pcd";
    summary->encoding = header.encoding == pcd::Encoding::kAscii    ? "ascii"
                        : header.encoding == pcd::Encoding::kBinary ? "binary"
                                                                    : "binary_compressed";
    ElementSummary vertex{"vertex", static_cast<std::int64_t>(n), {}};
    for (const pcd::Field& f : header.fields) {
      std::string property = pcd::TypeName(f.type) + " " + f.name;
      if (f.count != 1) property += "[" + std::to_string(f.count) + "]";
      vertex.properties.push_back(std::move(property));
    }
    summary->elements.push_back(std::move(vertex));
    summary->comments.push_back("PCD version " + (header.version.empty() ? "not given" : header.version) +
                                ", width " + std::to_string(header.width) + ", height " +
                                std::to_string(header.height));
  }
  return mesh;
}

}  // namespace pectus
