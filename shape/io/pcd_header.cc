// pectus: the PCD header (pcd_format.h): keywords, fields and counts, checked against the data's size.
#include <cstring>
#include <optional>

#include "shape/core/error.h"
#include "shape/io/pcd_format.h"
#include "shape/io/text_scan.h"

namespace pectus::pcd {
namespace {

// Counts beyond 2^40 points or elements are not files that fit on a disk: a corrupt header.
constexpr std::uint64_t kMaxCount = std::uint64_t{1} << 40;

// LZF turns at most 3 bytes into 264 (a back reference of the longest length): a block that claims more
// than 100 times its size is corrupt, whatever its header says.
constexpr std::uint64_t kMaxLzfRatio = 100;

std::optional<std::uint64_t> Product(std::uint64_t a, std::uint64_t b) {
  std::uint64_t p = 0;
  if (__builtin_mul_overflow(a, b, &p)) return std::nullopt;
  return p;
}

// One header line: its keyword, its values and its number.
struct Line {
  std::string_view key;
  std::vector<std::string_view> values;
  std::int64_t number = 0;
};

class HeaderParser {
 public:
  HeaderParser(std::string_view bytes, const std::string& name) : bytes_(bytes), name_(name) {}

  Header Parse();

 private:
  [[noreturn]] void Fail(const std::string& message, std::int64_t line = 0) const {
    ThrowBadInput(name_, message, line);
  }
  std::uint64_t Count(std::string_view token, const Line& line) const {
    std::int64_t v = 0;
    if (!text::ParseInt(token, &v) || v < 0 || static_cast<std::uint64_t>(v) > kMaxCount) {
      Fail("PCD header: " + text::Quoted(token) + " is not a valid count", line.number);
    }
    return static_cast<std::uint64_t>(v);
  }
  std::uint64_t OneCount(const Line& line) const {
    if (line.values.size() != 1)
      Fail("PCD header: " + std::string(line.key) + " needs one number", line.number);
    return Count(line.values[0], line);
  }
  void ReadLine(const Line& line);
  void CheckFields();
  void CheckPoints();
  void CheckDataSize();

  std::string_view bytes_;
  const std::string& name_;
  Header header_;
  std::vector<std::string_view> seen_;  // keywords read so far: each may come once
  std::vector<std::uint64_t> sizes_;
  std::vector<std::string_view> types_;
  std::vector<std::uint64_t> counts_;
  std::optional<std::uint64_t> width_, height_, points_;
  std::int64_t fields_line_ = 0;
};

void HeaderParser::ReadLine(const Line& line) {
  const std::string_view key = line.key;
  for (std::string_view seen : seen_) {
    const bool fields = (seen == "FIELDS" || seen == "COLUMNS") && (key == "FIELDS" || key == "COLUMNS");
    if (seen == key || fields) Fail("PCD header: " + std::string(key) + " is given twice", line.number);
  }
  seen_.push_back(key);
  if (key == "VERSION") {
    // PCL's own files said ".7" before they said "0.7".
    const std::string_view v = line.values.size() == 1 ? line.values[0] : std::string_view();
    if (v == "0.5" || v == "0.6" || v == "0.7" || v == ".5" || v == ".6" || v == ".7") {
      header_.version = v.front() == '.' ? "0" + std::string(v) : std::string(v);
    } else {
      Fail("PCD header: VERSION " + text::Quoted(v) + " is not 0.5, 0.6 or 0.7", line.number);
    }
  } else if (key == "FIELDS" || key == "COLUMNS") {
    if (line.values.empty()) Fail("PCD header: FIELDS names no field", line.number);
    for (std::string_view v : line.values) header_.fields.push_back(Field{.name = std::string(v)});
    fields_line_ = line.number;
  } else if (key == "SIZE") {
    for (std::string_view v : line.values) {
      sizes_.push_back(Count(v, line));
      if (sizes_.back() != 1 && sizes_.back() != 2 && sizes_.back() != 4 && sizes_.back() != 8)
        Fail("PCD header: field size " + text::Quoted(v) + " is not 1, 2, 4 or 8 bytes", line.number);
    }
  } else if (key == "TYPE") {
    for (std::string_view v : line.values) {
      if (v != "I" && v != "U" && v != "F")
        Fail("PCD header: field type " + text::Quoted(v) + " is not I, U or F", line.number);
      types_.push_back(v);
    }
  } else if (key == "COUNT") {
    for (std::string_view v : line.values) {
      counts_.push_back(Count(v, line));
      if (counts_.back() == 0 || counts_.back() > 0x7FFFFFFF)
        Fail("PCD header: field count " + text::Quoted(v) + " is not between 1 and 2^31 - 1", line.number);
    }
  } else if (key == "WIDTH") {
    width_ = OneCount(line);
  } else if (key == "HEIGHT") {
    height_ = OneCount(line);
  } else if (key == "POINTS") {
    points_ = OneCount(line);
  } else if (key == "VIEWPOINT") {
    // The sensor's pose (tx ty tz qw qx qy qz): checked, not applied (the points are kept as stored).
    double v = 0;
    bool numbers = line.values.size() == 7;
    for (std::string_view t : line.values) numbers = numbers && text::ParseDouble(t, &v);
    if (!numbers) Fail("PCD header: VIEWPOINT needs 7 numbers (tx ty tz qw qx qy qz)", line.number);
  } else if (key == "DATA") {
    const std::string_view v = line.values.size() == 1 ? line.values[0] : std::string_view();
    if (v == "ascii") {
      header_.encoding = Encoding::kAscii;
    } else if (v == "binary") {
      header_.encoding = Encoding::kBinary;
    } else if (v == "binary_compressed") {
      header_.encoding = Encoding::kBinaryCompressed;
    } else {
      Fail("PCD header: unknown DATA " + text::Quoted(v) + " (ascii, binary or binary_compressed)",
           line.number);
    }
  } else {
    // Keywords in capitals only, as PCL writes them.
    Fail("not a PCD file: unexpected " + text::Quoted(key) + " in the header", line.number);
  }
}

// Every field gets its size, type and count; the types fit the sizes; the point's bytes add up.
void HeaderParser::CheckFields() {
  std::vector<Field>& fields = header_.fields;
  if (fields.empty()) Fail("PCD header has no FIELDS");
  const auto per_field = [&](std::size_t given, const char* what) {
    if (given != fields.size()) {
      Fail("PCD header: " + std::string(what) + " gives " + std::to_string(given) + " values for " +
               std::to_string(fields.size()) + " fields",
           fields_line_);
    }
  };
  // PCD 0.5 files may leave out SIZE, TYPE and COUNT: 4-byte floats, one each, as PCL reads them. A
  // missing TYPE is F whatever SIZE says: PCL wrote 4-byte floats into fields of SIZE 1 past the end of
  // its buffer (the heap corruption fuzz_pcd found), pectus refuses such a header.
  if (sizes_.empty()) sizes_.assign(fields.size(), 4);
  if (types_.empty()) types_.assign(fields.size(), "F");
  if (counts_.empty()) counts_.assign(fields.size(), 1);
  per_field(sizes_.size(), "SIZE");
  per_field(types_.size(), "TYPE");
  per_field(counts_.size(), "COUNT");
  for (std::size_t f = 0; f < fields.size(); ++f) {
    Field& field = fields[f];
    field.size = sizes_[f];
    field.count = counts_[f];
    const int log_size = field.size == 1 ? 0 : field.size == 2 ? 1 : field.size == 4 ? 2 : 3;
    if (types_[f] == "F") {
      if (field.size != 4 && field.size != 8) {
        Fail("PCD header: field '" + field.name + "' has TYPE F and SIZE " + std::to_string(field.size) +
                 " (a float is 4 or 8 bytes)",
             fields_line_);
      }
      field.type = field.size == 4 ? Type::kFloat32 : Type::kFloat64;
    } else {
      static constexpr Type kSigned[] = {Type::kInt8, Type::kInt16, Type::kInt32, Type::kInt64};
      static constexpr Type kUnsigned[] = {Type::kUint8, Type::kUint16, Type::kUint32, Type::kUint64};
      field.type = types_[f] == "I" ? kSigned[log_size] : kUnsigned[log_size];
    }
    // Sizes are at most 8 and counts below 2^31: these sums overflow only past 2^30 fields.
    field.offset = header_.point_bytes;
    if (__builtin_add_overflow(header_.point_bytes, field.bytes(), &header_.point_bytes) ||
        __builtin_add_overflow(header_.values_per_point, field.count, &header_.values_per_point)) {
      Fail("PCD header: the fields of a point add up to more bytes than can be counted", fields_line_);
    }
  }
}

// WIDTH x HEIGHT points, as POINTS says if it is there.
void HeaderParser::CheckPoints() {
  if (!width_ && !points_) Fail("PCD header gives neither WIDTH nor POINTS");
  if (!width_ && height_) Fail("PCD header gives HEIGHT but no WIDTH");
  header_.width = width_ ? *width_ : *points_;
  header_.height = height_ ? *height_ : 1;
  const std::optional<std::uint64_t> product = Product(header_.width, header_.height);
  if (!product || *product > kMaxCount) {
    Fail("PCD header: WIDTH " + std::to_string(header_.width) + " x HEIGHT " +
         std::to_string(header_.height) + " is too many points");
  }
  if (points_ && *points_ != *product) {
    Fail("PCD header: POINTS " + std::to_string(*points_) + " is not WIDTH x HEIGHT = " +
         std::to_string(header_.width) + " x " + std::to_string(header_.height));
  }
  header_.points = *product;
}

// Enough bytes for what the header declares, before anything is allocated.
void HeaderParser::CheckDataSize() {
  const std::uint64_t available = bytes_.size() - header_.data_offset;
  const std::uint64_t n = header_.points;
  const auto truncated = [&](const std::string& needs) {
    Fail("truncated PCD file: the header declares " + std::to_string(n) + " points (" + needs +
         ") but the data holds " + std::to_string(available) + " bytes");
  };
  if (n == 0) return;
  if (header_.encoding == Encoding::kAscii) {
    // Every value takes at least a digit and a separator.
    const std::optional<std::uint64_t> values = Product(n, header_.values_per_point);
    if (!values || *values > available / 2 + 1)
      truncated(std::to_string(header_.values_per_point) + " numbers each");
  } else if (header_.encoding == Encoding::kBinary) {
    const std::optional<std::uint64_t> needed = Product(n, header_.point_bytes);
    if (!needed || *needed > available) truncated(std::to_string(header_.point_bytes) + " bytes each");
  } else {
    if (available < 8) truncated("a compressed block");
    std::memcpy(&header_.compressed_bytes, bytes_.data() + header_.data_offset, 4);
    std::memcpy(&header_.uncompressed_bytes, bytes_.data() + header_.data_offset + 4, 4);
    if (header_.compressed_bytes > available - 8)
      truncated(std::to_string(header_.compressed_bytes) + " compressed bytes");
    // The block holds every field but the padding, field after field.
    std::uint64_t value_bytes = 0;
    for (const Field& f : header_.fields) value_bytes += f.is_padding() ? 0 : f.bytes();
    const std::optional<std::uint64_t> needed = Product(n, value_bytes);
    if (!needed || *needed != header_.uncompressed_bytes) {
      Fail("PCD compressed block holds " + std::to_string(header_.uncompressed_bytes) +
           " bytes but the header's " + std::to_string(n) + " points need " +
           (needed ? std::to_string(*needed) : std::string("more")));
    }
    if (header_.uncompressed_bytes / kMaxLzfRatio > std::uint64_t{header_.compressed_bytes} + 64) {
      Fail("PCD compressed block of " + std::to_string(header_.compressed_bytes) +
           " bytes cannot expand to " + std::to_string(header_.uncompressed_bytes) +
           " (LZF expands at most about 100-fold)");
    }
  }
}

Header HeaderParser::Parse() {
  text::LineReader lines(bytes_);
  std::string_view text;
  bool has_data = false;
  while (!has_data && lines.Next(&text)) {
    Line line;
    line.number = lines.number();
    std::string_view rest = text;
    line.key = text::NextToken(&rest);
    if (line.key.empty() || line.key.front() == '#') continue;
    for (std::string_view t = text::NextToken(&rest); !t.empty(); t = text::NextToken(&rest))
      line.values.push_back(t);
    ReadLine(line);
    if (line.key == "DATA") {
      // The data starts after this line's '\n' (LineReader drops it and a '\r' before it).
      const std::size_t end = static_cast<std::size_t>(text.data() - bytes_.data()) + text.size();
      const std::size_t newline = bytes_.find('\n', end);
      header_.data_offset = newline == std::string_view::npos ? bytes_.size() : newline + 1;
      header_.data_line = line.number + 1;
      has_data = true;
    }
  }
  if (!has_data) Fail("not a PCD file (no DATA line in the header)");
  CheckFields();
  CheckPoints();
  CheckDataSize();
  return header_;
}

}  // namespace

std::string TypeName(Type type) {
  switch (type) {
    case Type::kInt8: return "char";
    case Type::kUint8: return "uchar";
    case Type::kInt16: return "short";
    case Type::kUint16: return "ushort";
    case Type::kInt32: return "int";
    case Type::kUint32: return "uint";
    case Type::kInt64: return "long";
    case Type::kUint64: return "ulong";
    case Type::kFloat32: return "float";
    case Type::kFloat64: return "double";
  }
  return "?";
}

Header ParseHeader(std::string_view bytes, const std::string& name) {
  return HeaderParser(bytes, name).Parse();
}

}  // namespace pectus::pcd
