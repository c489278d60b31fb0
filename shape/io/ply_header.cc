// pectus: the PLY header, the mapping of vertex properties to a point cloud, and message helpers.
#include <charconv>
#include <system_error>

#if defined(__linux__)
#include <sys/mman.h>
#endif

#include "shape/core/error.h"
#include "shape/io/ply_format.h"

namespace pectus::ply {

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
      if (words.size() != 3)
        ThrowBadInput(name, "format line must read 'format <encoding> 1.0'", line_number);
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
      if (words.size() != 3)
        ThrowBadInput(name, "element line must read 'element <name> <count>'", line_number);
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
        property.declaration =
            "list " + std::string(words[2]) + " " + std::string(words[3]) + " " + property.name;
      } else {
        property.declaration = std::string(words[1]) + " " + property.name;
      }
      if (element.FindProperty(property.name) >= 0) {
        ThrowBadInput(
            name,
            "property " + Quote(property.name) + " of element " + Quote(element.name) + " is declared twice",
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

std::string Plural(const Element& e) {
  if (e.name == "vertex") return "vertices";
  if (e.name == "face") return "faces";
  return Quote(e.name) + " items";
}
std::string Singular(const Element& e) {
  if (e.name == "vertex" || e.name == "face") return e.name;
  return Quote(e.name) + " item";
}

std::string PropertyOf(const Property& p, const Element& e, std::int64_t item) {
  return "property " + Quote(p.name) + " of " + Singular(e) + " " + std::to_string(item);
}

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

}  // namespace pectus::ply
