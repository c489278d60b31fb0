// PCD reader: an adaptor over PCL's reader (ascii, binary and binary_compressed), converting PCL's
// untyped PCLPointCloud2 into pectus types. Nothing outside this file sees PCL.
#include <pcl/PCLPointCloud2.h>
#include <pcl/console/print.h>
#include <pcl/exceptions.h>
#include <pcl/io/pcd_io.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "shape/core/error.h"
#include "shape/core/log.h"
#include "shape/io/format_parsers.h"
#include "shape/io/mapped_file.h"
#include "shape/io/text_scan.h"

namespace pectus {
namespace {

using pcl::PCLPointField;

// PCL prints its own errors to the console; pectus reports them as its Error instead.
class QuietPcl {
 public:
  QuietPcl() : level_(pcl::console::getVerbosityLevel()) {
    pcl::console::setVerbosityLevel(pcl::console::L_ALWAYS);
  }
  ~QuietPcl() { pcl::console::setVerbosityLevel(level_); }
  QuietPcl(const QuietPcl&) = delete;
  QuietPcl& operator=(const QuietPcl&) = delete;

 private:
  pcl::console::VERBOSITY_LEVEL level_;
};

std::string TypeName(std::uint8_t datatype) {
  switch (datatype) {
    case PCLPointField::INT8: return "char";
    case PCLPointField::UINT8: return "uchar";
    case PCLPointField::INT16: return "short";
    case PCLPointField::UINT16: return "ushort";
    case PCLPointField::INT32: return "int";
    case PCLPointField::UINT32: return "uint";
    case PCLPointField::INT64: return "long";
    case PCLPointField::UINT64: return "ulong";
    case PCLPointField::FLOAT32: return "float";
    case PCLPointField::FLOAT64: return "double";
    default: return "unknown";
  }
}

template <typename T>
double Load(const std::uint8_t* p) {
  T v;
  std::memcpy(&v, p, sizeof v);
  return static_cast<double>(v);
}

// The value of a one-element field at `p`, as a double.
double LoadAsDouble(std::uint8_t datatype, const std::uint8_t* p) {
  switch (datatype) {
    case PCLPointField::INT8: return Load<std::int8_t>(p);
    case PCLPointField::UINT8: return Load<std::uint8_t>(p);
    case PCLPointField::INT16: return Load<std::int16_t>(p);
    case PCLPointField::UINT16: return Load<std::uint16_t>(p);
    case PCLPointField::INT32: return Load<std::int32_t>(p);
    case PCLPointField::UINT32: return Load<std::uint32_t>(p);
    case PCLPointField::INT64: return Load<std::int64_t>(p);
    case PCLPointField::UINT64: return Load<std::uint64_t>(p);
    case PCLPointField::FLOAT32: return Load<float>(p);
    case PCLPointField::FLOAT64: return Load<double>(p);
    default: return std::nan("");
  }
}

std::size_t TypeSize(std::uint8_t datatype) {
  switch (datatype) {
    case PCLPointField::INT8:
    case PCLPointField::UINT8: return 1;
    case PCLPointField::INT16:
    case PCLPointField::UINT16: return 2;
    case PCLPointField::INT32:
    case PCLPointField::UINT32:
    case PCLPointField::FLOAT32: return 4;
    case PCLPointField::INT64:
    case PCLPointField::UINT64:
    case PCLPointField::FLOAT64: return 8;
    default: return 0;
  }
}

const PCLPointField* FindField(const pcl::PCLPointCloud2& cloud, const std::string& name) {
  for (const PCLPointField& f : cloud.fields) {
    if (f.name == name) return &f;
  }
  return nullptr;
}

// What the header of a PCD file declares, read by pectus before PCL sees the file: PCL trusts the header
// and reads past the end of a truncated file (a crash) or allocates whatever WIDTH x HEIGHT asks for.
struct PcdLayout {
  std::string encoding;           // "ascii", "binary" or "binary_compressed"
  std::uint64_t points = 0;       // POINTS, or WIDTH x HEIGHT
  std::uint64_t point_bytes = 0;  // sum of SIZE x COUNT
  std::size_t data_offset = 0;    // first byte after the DATA line
};

std::uint64_t HeaderNumber(std::string_view token, const std::string& path, std::int64_t line) {
  std::int64_t v = 0;
  if (!text::ParseInt(token, &v) || v < 0 || v > (std::int64_t{1} << 40)) {
    ThrowBadInput(path, "PCD header: " + text::Quoted(token) + " is not a valid count", line);
  }
  return static_cast<std::uint64_t>(v);
}

PcdLayout ReadPcdLayout(std::string_view bytes, const std::string& path) {
  PcdLayout layout;
  std::vector<std::uint64_t> sizes, counts;
  std::size_t num_fields = 0;
  std::uint64_t width = 0, height = 1;
  bool has_points = false;
  text::LineReader lines(bytes);
  std::string_view line;
  std::size_t consumed = 0;
  while (lines.Next(&line)) {
    consumed = static_cast<std::size_t>(line.data() - bytes.data()) + line.size();
    while (consumed < bytes.size() && bytes[consumed] != '\n') ++consumed;
    consumed = std::min(consumed + 1, bytes.size());
    std::string_view rest = line;
    const std::string_view key = text::NextToken(&rest);
    const std::int64_t number = lines.number();
    if (key.empty() || key.front() == '#') continue;
    // Keywords in capitals, as PCL matches them: a header PCL reads otherwise than this check (e.g. a
    // "VErSION" line) made PCL's reader dereference a null pointer (found by fuzzing).
    std::vector<std::string_view> values;
    for (std::string_view t = text::NextToken(&rest); !t.empty(); t = text::NextToken(&rest))
      values.push_back(t);
    if (key == "FIELDS" || key == "COLUMNS") {
      num_fields = values.size();
    } else if (key == "SIZE") {
      for (std::string_view v : values) {
        sizes.push_back(HeaderNumber(v, path, number));
        if (sizes.back() != 1 && sizes.back() != 2 && sizes.back() != 4 && sizes.back() != 8) {
          ThrowBadInput(path, "PCD header: field size " + text::Quoted(v) + " is not 1, 2, 4 or 8 bytes",
                        number);
        }
      }
    } else if (key == "COUNT") {
      for (std::string_view v : values) {
        counts.push_back(HeaderNumber(v, path, number));
        if (counts.back() > 0x7FFFFFFF)
          ThrowBadInput(path, "PCD header: field count " + text::Quoted(v) + " is too large", number);
      }
    } else if (key == "WIDTH" && values.size() == 1) {
      width = HeaderNumber(values[0], path, number);
    } else if (key == "HEIGHT" && values.size() == 1) {
      height = HeaderNumber(values[0], path, number);
    } else if (key == "POINTS" && values.size() == 1) {
      layout.points = HeaderNumber(values[0], path, number);
      has_points = true;
    } else if (key == "DATA") {
      if (values.size() != 1) ThrowBadInput(path, "PCD header: DATA needs one word", number);
      layout.encoding = text::ToLowerAscii(values[0]);
      layout.data_offset = consumed;
      break;
    } else if (key != "VERSION" && key != "TYPE" && key != "VIEWPOINT") {
      ThrowBadInput(path, "not a PCD file: unexpected " + text::Quoted(key) + " in the header", number);
    }
  }
  if (layout.encoding.empty()) ThrowBadInput(path, "not a PCD file (no DATA line in the header)");
  if (layout.encoding != "ascii" && layout.encoding != "binary" && layout.encoding != "binary_compressed") {
    ThrowBadInput(path, "PCD header: unknown DATA " + text::Quoted(layout.encoding));
  }
  if (num_fields == 0) ThrowBadInput(path, "PCD header has no FIELDS");
  if (sizes.size() != num_fields) ThrowBadInput(path, "PCD header: SIZE does not give one size per field");
  if (counts.empty()) counts.assign(num_fields, 1);
  if (counts.size() != num_fields) ThrowBadInput(path, "PCD header: COUNT does not give one count per field");
  std::uint64_t values_per_point = 0;
  for (std::size_t f = 0; f < num_fields; ++f) {
    layout.point_bytes += sizes[f] * counts[f];
    values_per_point += counts[f];
  }
  if (!has_points) layout.points = width * height;

  // Enough bytes for what the header declares?
  const std::size_t available = bytes.size() - layout.data_offset;
  const double needed = static_cast<double>(layout.points) * static_cast<double>(layout.point_bytes);
  const auto truncated = [&](const std::string& needs) {
    ThrowBadInput(path, "truncated PCD file: the header declares " + std::to_string(layout.points) +
                            " points (" + needs + ") but the data holds " + std::to_string(available) +
                            " bytes");
  };
  if (layout.encoding == "ascii") {
    // Every value takes at least a digit and a separator.
    if (static_cast<double>(layout.points) * static_cast<double>(values_per_point) * 2 >
        static_cast<double>(available) + 1) {
      truncated(std::to_string(values_per_point) + " numbers each");
    }
  } else if (layout.encoding == "binary") {
    if (needed > static_cast<double>(available))
      truncated(std::to_string(layout.point_bytes) + " bytes each");
  } else if (layout.points > 0) {
    // binary_compressed: uint32 compressed size, uint32 uncompressed size, then the LZF data.
    std::uint32_t sizes_le[2] = {0, 0};
    if (available < 8) truncated("a compressed block");
    std::memcpy(sizes_le, bytes.data() + layout.data_offset, 8);
    if (sizes_le[0] > available - 8) truncated(std::to_string(sizes_le[0]) + " compressed bytes");
    // LZF expands at most about 100-fold: a larger claim is a corrupt header, not a real file.
    if (static_cast<double>(sizes_le[1]) != needed || sizes_le[1] / 100 > sizes_le[0] + 64) {
      ThrowBadInput(path, "PCD compressed block holds " + std::to_string(sizes_le[1]) +
                              " bytes but the header's " + std::to_string(layout.points) + " points need " +
                              std::to_string(needed));
    }
  }
  return layout;
}

}  // namespace

TriangleMesh ReadPcdFile(const std::string& path, FileSummary* summary) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) ThrowBadInput(path, "no such file");
  PcdLayout layout;
  {
    const MappedFile file(path);
    if (file.bytes().empty()) ThrowBadInput(path, "file is empty");
    layout = ReadPcdLayout(file.bytes(), path);
  }

  pcl::PCLPointCloud2 cloud;
  Eigen::Vector4f origin;
  Eigen::Quaternionf orientation;
  int version = pcl::PCDReader::PCD_V7;
  {
    QuietPcl quiet;
    pcl::PCDReader reader;
    try {
      const int status = layout.points == 0 ? reader.readHeader(path, cloud)
                                            : reader.read(path, cloud, origin, orientation, version);
      if (status < 0) ThrowBadInput(path, "PCL cannot read this PCD file (malformed header or data)");
    } catch (const pcl::PCLException& e) {
      ThrowBadInput(path, std::string("PCL cannot read this PCD file: ") + e.detailedMessage());
    } catch (const std::bad_alloc&) {
      ThrowBadInput(path, "PCD header declares more points than can be held in memory");
    }
  }

  const std::size_t n = layout.points == 0 ? 0 : static_cast<std::size_t>(cloud.width) * cloud.height;
  if (cloud.point_step == 0 || cloud.data.size() < n * cloud.point_step) {
    ThrowBadInput(path, "PCD data holds fewer bytes than its header's " + std::to_string(n) + " points need");
  }
  for (const PCLPointField& f : cloud.fields) {
    if (f.offset + TypeSize(f.datatype) * std::max<std::size_t>(f.count, 1) > cloud.point_step) {
      ThrowBadInput(path, "PCD field '" + f.name + "' lies outside its point");
    }
  }
  const PCLPointField* xyz[3] = {FindField(cloud, "x"), FindField(cloud, "y"), FindField(cloud, "z")};
  if (!xyz[0] || !xyz[1] || !xyz[2]) ThrowBadInput(path, "PCD file has no x, y, z fields");
  const PCLPointField* normal[3] = {FindField(cloud, "normal_x"), FindField(cloud, "normal_y"),
                                    FindField(cloud, "normal_z")};
  const bool has_normals = normal[0] && normal[1] && normal[2];
  const PCLPointField* rgb = FindField(cloud, "rgb");
  if (!rgb) rgb = FindField(cloud, "rgba");
  if (rgb && TypeSize(rgb->datatype) != 4) rgb = nullptr;
  std::vector<const PCLPointField*> scalars;
  for (const PCLPointField& f : cloud.fields) {
    const bool known = &f == xyz[0] || &f == xyz[1] || &f == xyz[2] || &f == rgb ||
                       (has_normals && (&f == normal[0] || &f == normal[1] || &f == normal[2]));
    // Padding ("_") and multi-element fields (descriptors such as fpfh[33]) are not per-point scalars.
    if (!known && f.name != "_" && f.count == 1 && TypeSize(f.datatype) > 0) scalars.push_back(&f);
  }

  // Organized clouds mark missing returns with NaN positions: those points are left out.
  const auto point = [&](std::size_t i) { return cloud.data.data() + i * cloud.point_step; };
  std::vector<std::size_t> keep;
  keep.reserve(n);
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint8_t* p = point(i);
    bool finite = true;
    for (const PCLPointField* f : xyz)
      finite = finite && std::isfinite(LoadAsDouble(f->datatype, p + f->offset));
    if (finite) keep.push_back(i);
  }
  if (keep.size() < n) {
    Warn(path + ": " + std::to_string(n - keep.size()) + " of " + std::to_string(n) +
         " points have no valid position (NaN) and were left out");
  }

  const auto m = static_cast<Eigen::Index>(keep.size());
  TriangleMesh mesh;
  PointCloud& out = mesh.vertices;
  out.positions.resize(m, 3);
  if (has_normals) out.normals.resize(m, 3);
  if (rgb) out.colors.resize(m, 3);
  for (const PCLPointField* f : scalars) out.scalars[f->name].resize(m);
  for (Eigen::Index j = 0; j < m; ++j) {
    const std::uint8_t* p = point(keep[static_cast<std::size_t>(j)]);
    for (int k = 0; k < 3; ++k) {
      out.positions(j, k) = LoadAsDouble(xyz[k]->datatype, p + xyz[k]->offset);
      if (has_normals) out.normals(j, k) = LoadAsDouble(normal[k]->datatype, p + normal[k]->offset);
    }
    if (rgb) {
      // Packed 0x(AA)RRGGBB in a float or uint32.
      std::uint32_t packed;
      std::memcpy(&packed, p + rgb->offset, 4);
      out.colors.row(j) << static_cast<std::uint8_t>((packed >> 16) & 0xFF),
          static_cast<std::uint8_t>((packed >> 8) & 0xFF), static_cast<std::uint8_t>(packed & 0xFF);
    }
    for (const PCLPointField* f : scalars) out.scalars[f->name][j] = LoadAsDouble(f->datatype, p + f->offset);
  }
  mesh.faces.resize(0, 3);

  if (summary) {
    *summary = FileSummary{};
    summary->format = "pcd";
    summary->encoding = layout.encoding;
    ElementSummary vertex{"vertex", static_cast<std::int64_t>(n), {}};
    for (const PCLPointField& f : cloud.fields) {
      std::string property = TypeName(f.datatype) + " " + f.name;
      if (f.count != 1) property += "[" + std::to_string(f.count) + "]";
      vertex.properties.push_back(std::move(property));
    }
    summary->elements.push_back(std::move(vertex));
    summary->comments.push_back("PCD version " +
                                std::string(version == pcl::PCDReader::PCD_V6 ? "0.6" : "0.7") + ", width " +
                                std::to_string(cloud.width) + ", height " + std::to_string(cloud.height));
  }
  return mesh;
}

}  // namespace pectus
