// STL reader and writer, binary and ASCII. STL stores each triangle's corners by value; the reader welds
// identical positions (exact equality) back into an indexed mesh.
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <string>
#include <unordered_map>
#include <vector>

#include "shape/core/error.h"
#include "shape/io/format_parsers.h"
#include "shape/io/text_scan.h"

namespace pectus {
namespace {

constexpr std::size_t kHeaderBytes = 80;
constexpr std::size_t kRecordBytes = 50;  // normal, 3 corners (12 floats), uint16 attribute

// Welds corners by exact position equality, in order of first appearance.
class VertexWelder {
 public:
  explicit VertexWelder(std::size_t expected_corners) {
    index_.reserve(expected_corners / 2);
    positions_.reserve(expected_corners / 2 * 3);
  }

  std::int32_t Add(double x, double y, double z) {
    // +0.0 and -0.0 are the same position.
    const Key key{Bits(x), Bits(y), Bits(z)};
    const auto next = static_cast<std::int32_t>(positions_.size() / 3);
    const auto [it, inserted] = index_.try_emplace(key, next);
    if (inserted) positions_.insert(positions_.end(), {x + 0.0, y + 0.0, z + 0.0});
    return it->second;
  }
  Points3 Positions() const {
    return Eigen::Map<const Points3>(positions_.data(), static_cast<Eigen::Index>(positions_.size() / 3), 3);
  }

 private:
  struct Key {
    std::uint64_t x, y, z;
    bool operator==(const Key&) const = default;
  };
  struct KeyHash {
    std::size_t operator()(const Key& k) const {
      std::uint64_t h = k.x * 0x9E3779B97F4A7C15ull;
      h ^= (k.y + 0x632BE59BD9B4E019ull + (h << 6) + (h >> 2)) * 0xBF58476D1CE4E5B9ull;
      h ^= (k.z + 0x94D049BB133111EBull + (h << 6) + (h >> 2)) * 0x94D049BB133111EBull;
      return static_cast<std::size_t>(h ^ (h >> 31));
    }
  };
  static std::uint64_t Bits(double v) { return std::bit_cast<std::uint64_t>(v + 0.0); }

  std::unordered_map<Key, std::int32_t, KeyHash> index_;
  std::vector<double> positions_;
};

std::uint32_t ReadU32(const char* p) {
  std::uint32_t v;
  std::memcpy(&v, p, 4);
  if constexpr (std::endian::native == std::endian::big) v = __builtin_bswap32(v);
  return v;
}

float ReadF32(const char* p) { return std::bit_cast<float>(ReadU32(p)); }

// A binary header that starts with "solid" is common; text after it is an ASCII file only if it reads as
// text.
bool LooksLikeAscii(std::string_view bytes) {
  std::size_t i = 0;
  while (i < bytes.size() && text::IsSpace(bytes[i])) ++i;
  if (!text::StartsWithNoCase(bytes.substr(i), "solid")) return false;
  const std::string_view head = bytes.substr(0, 512);
  for (char c : head) {
    const auto u = static_cast<unsigned char>(c);
    if (u == 0 || (u < 0x20 && !text::IsSpace(c) && c != '\n')) return false;
  }
  return true;
}

std::string HeaderText(std::string_view header) {
  std::string out;
  for (char c : header) {
    if (c == '\0') break;
    out += (c >= 0x20 && c < 0x7F) ? c : ' ';
  }
  return std::string(text::Trim(out));
}

TriangleMesh ParseBinary(std::string_view bytes, const std::string& name, FileSummary* summary) {
  if (bytes.size() < kHeaderBytes + 4) {
    ThrowBadInput(name, "not an STL file: " + std::to_string(bytes.size()) +
                            " bytes is too short for a binary STL (84-byte header) and the file does not "
                            "start with 'solid'");
  }
  const std::uint64_t count = ReadU32(bytes.data() + kHeaderBytes);
  const std::uint64_t needed = kHeaderBytes + 4 + kRecordBytes * count;
  if (needed != bytes.size()) {
    ThrowBadInput(
        name, std::string(needed > bytes.size() ? "truncated binary STL" : "binary STL has extra bytes") +
                  ": header says " + std::to_string(count) + " triangles (needs " + std::to_string(needed) +
                  " bytes) but the file has " + std::to_string(bytes.size()));
  }
  if (count > static_cast<std::uint64_t>(std::numeric_limits<std::int32_t>::max()) / 3) {
    ThrowBadInput(name, "too many triangles (" + std::to_string(count) + ")");
  }
  const auto n = static_cast<Eigen::Index>(count);
  TriangleMesh mesh;
  mesh.faces.resize(n, 3);
  VertexWelder welder(static_cast<std::size_t>(3 * count));
  const char* record = bytes.data() + kHeaderBytes + 4;
  for (Eigen::Index f = 0; f < n; ++f, record += kRecordBytes) {
    for (int k = 0; k < 3; ++k) {
      const char* p = record + 12 + 12 * k;
      const double x = ReadF32(p), y = ReadF32(p + 4), z = ReadF32(p + 8);
      if (!std::isfinite(x) || !std::isfinite(y) || !std::isfinite(z)) {
        ThrowBadInput(name,
                      "triangle " + std::to_string(f + 1) + " has a non-finite coordinate (NaN or Inf)");
      }
      mesh.faces(f, k) = welder.Add(x, y, z);
    }
  }
  mesh.vertices.positions = welder.Positions();
  if (summary) {
    *summary = FileSummary{};
    summary->format = "stl";
    summary->encoding = "binary";
    summary->elements.push_back({"vertex", mesh.num_vertices(), {"float x", "float y", "float z"}});
    summary->elements.push_back({"face", n, {"float normal[3]", "float vertex[3][3]", "ushort attribute"}});
    const std::string header = HeaderText(bytes.substr(0, kHeaderBytes));
    if (!header.empty()) summary->comments.push_back(header);
  }
  return mesh;
}

TriangleMesh ParseAscii(std::string_view bytes, const std::string& name, FileSummary* summary) {
  text::LineReader lines(bytes);
  const auto fail = [&](const std::string& message) { ThrowBadInput(name, message, lines.number()); };
  VertexWelder welder(bytes.size() / 40);
  std::vector<std::int32_t> corners;  // 3 per triangle
  std::vector<std::int32_t> loop;     // the corners of the current facet
  std::vector<std::string> solids;
  enum class State { kOutside, kSolid, kFacet, kLoop, kEndLoop } state = State::kOutside;
  std::string_view line;
  while (lines.Next(&line)) {
    std::string_view rest = line;
    const std::string_view word = text::NextToken(&rest);
    if (word.empty()) continue;
    const auto is = [&](std::string_view keyword) { return text::EqualsNoCase(word, keyword); };
    const auto expect = [&](State wanted, const char* after) {
      if (state != wanted)
        fail("unexpected '" + std::string(word.substr(0, 40)) + "' (expected it " + after + ")");
    };
    if (is("solid")) {
      expect(State::kOutside, "at the start or after 'endsolid'");
      solids.emplace_back(text::Trim(rest));
      state = State::kSolid;
    } else if (is("facet")) {
      expect(State::kSolid, "after 'solid' or 'endfacet'");
      state = State::kFacet;  // the stored normal is recomputed by users who need it
    } else if (is("outer")) {
      expect(State::kFacet, "after 'facet normal'");
      loop.clear();
      state = State::kLoop;
    } else if (is("vertex")) {
      expect(State::kLoop, "inside 'outer loop'");
      double xyz[3];
      for (double& c : xyz) {
        const std::string_view token = text::NextToken(&rest);
        if (token.empty()) fail("a vertex needs 3 coordinates");
        if (!text::ParseDouble(token, &c)) fail("'" + std::string(token.substr(0, 40)) + "' is not a number");
        if (!std::isfinite(c)) fail("non-finite coordinate '" + std::string(token) + "' (NaN or Inf)");
      }
      if (!text::NextToken(&rest).empty()) fail("a vertex needs exactly 3 coordinates");
      loop.push_back(welder.Add(xyz[0], xyz[1], xyz[2]));
    } else if (is("endloop")) {
      expect(State::kLoop, "after the vertices");
      if (loop.size() < 3) fail("facet with " + std::to_string(loop.size()) + " vertices (needs 3)");
      for (std::size_t i = 1; i + 1 < loop.size(); ++i)
        corners.insert(corners.end(), {loop[0], loop[i], loop[i + 1]});
      state = State::kEndLoop;
    } else if (is("endfacet")) {
      expect(State::kEndLoop, "after 'endloop'");
      state = State::kSolid;
    } else if (is("endsolid")) {
      expect(State::kSolid, "after the last 'endfacet'");
      state = State::kOutside;
    } else {
      fail("unexpected '" + std::string(word.substr(0, 40)) + "' in an ASCII STL");
    }
  }
  // A missing final 'endsolid' is common and harmless; a file cut inside a facet is not.
  if (state != State::kOutside && state != State::kSolid) {
    ThrowBadInput(name, "ASCII STL ends inside a facet (truncated?)", lines.number());
  }
  if (corners.size() / 3 > static_cast<std::size_t>(std::numeric_limits<std::int32_t>::max())) {
    ThrowBadInput(name, "too many triangles");
  }
  TriangleMesh mesh;
  mesh.vertices.positions = welder.Positions();
  mesh.faces = Eigen::Map<const Faces3>(corners.data(), static_cast<Eigen::Index>(corners.size() / 3), 3);
  if (summary) {
    *summary = FileSummary{};
    summary->format = "stl";
    summary->encoding = "ascii";
    summary->elements.push_back({"vertex", mesh.num_vertices(), {"x", "y", "z"}});
    summary->elements.push_back({"face", mesh.num_faces(), {"normal", "vertex[3]"}});
    for (const std::string& solid : solids) {
      if (!solid.empty()) summary->comments.push_back("solid " + solid);
    }
  }
  return mesh;
}

Eigen::Vector3f FacetNormal(const TriangleMesh& mesh, Eigen::Index f) {
  const Eigen::Vector3d a = mesh.vertices.positions.row(mesh.faces(f, 0));
  const Eigen::Vector3d b = mesh.vertices.positions.row(mesh.faces(f, 1));
  const Eigen::Vector3d c = mesh.vertices.positions.row(mesh.faces(f, 2));
  const Eigen::Vector3d n = (b - a).cross(c - a);
  const double length = n.norm();
  return length > 0 ? Eigen::Vector3f((n / length).cast<float>()) : Eigen::Vector3f::Zero();
}

void AppendF32(float v, std::string* out) {
  std::uint32_t bits = std::bit_cast<std::uint32_t>(v);
  if constexpr (std::endian::native == std::endian::big) bits = __builtin_bswap32(bits);
  out->append(reinterpret_cast<const char*>(&bits), 4);
}

void Flush(std::string* buffer, std::ostream& out) {
  out.write(buffer->data(), static_cast<std::streamsize>(buffer->size()));
  buffer->clear();
}

void WriteBinary(std::ostream& out, const TriangleMesh& mesh, const WriteOptions& options) {
  // The header must not start with "solid", or readers that look at the first word take it for ASCII.
  std::string header = "pectus binary STL";
  if (!options.comment.empty()) header += ": " + options.comment;
  for (char& c : header) {
    if (c == '\n' || c == '\r') c = ' ';
  }
  header.resize(kHeaderBytes, ' ');
  std::string buffer = header;
  buffer.reserve(1 << 20);
  std::uint32_t count = static_cast<std::uint32_t>(mesh.num_faces());
  if constexpr (std::endian::native == std::endian::big) count = __builtin_bswap32(count);
  buffer.append(reinterpret_cast<const char*>(&count), 4);
  for (Eigen::Index f = 0; f < mesh.num_faces(); ++f) {
    const Eigen::Vector3f n = FacetNormal(mesh, f);
    for (int k = 0; k < 3; ++k) AppendF32(n[k], &buffer);
    for (int corner = 0; corner < 3; ++corner) {
      for (int k = 0; k < 3; ++k) {
        AppendF32(static_cast<float>(mesh.vertices.positions(mesh.faces(f, corner), k)), &buffer);
      }
    }
    buffer.append(2, '\0');
    if (buffer.size() > (1 << 20) - 64) Flush(&buffer, out);
  }
  Flush(&buffer, out);
}

void WriteAscii(std::ostream& out, const TriangleMesh& mesh, const WriteOptions& options) {
  std::string solid = options.comment.empty() ? "pectus" : options.comment;
  for (char& c : solid) {
    if (c == '\n' || c == '\r') c = ' ';
  }
  std::string buffer = "solid " + solid + "\n";
  buffer.reserve(1 << 20);
  for (Eigen::Index f = 0; f < mesh.num_faces(); ++f) {
    const Eigen::Vector3f n = FacetNormal(mesh, f);
    buffer += "  facet normal";
    for (int k = 0; k < 3; ++k) {
      buffer += ' ';
      text::AppendNumber(n[k], &buffer);
    }
    buffer += "\n    outer loop\n";
    for (int corner = 0; corner < 3; ++corner) {
      buffer += "      vertex";
      for (int k = 0; k < 3; ++k) {
        buffer += ' ';
        text::AppendNumber(mesh.vertices.positions(mesh.faces(f, corner), k), &buffer);
      }
      buffer += '\n';
    }
    buffer += "    endloop\n  endfacet\n";
    if (buffer.size() > (1 << 20) - 512) Flush(&buffer, out);
  }
  buffer += "endsolid " + solid + "\n";
  Flush(&buffer, out);
}

}  // namespace

TriangleMesh ParseStl(std::string_view bytes, const std::string& name, FileSummary* summary) {
  if (bytes.empty()) ThrowBadInput(name, "file is empty");
  // Binary when the size matches the triangle count exactly, whatever the header's first word.
  if (bytes.size() >= kHeaderBytes + 4) {
    const std::uint64_t count = ReadU32(bytes.data() + kHeaderBytes);
    if (kHeaderBytes + 4 + kRecordBytes * count == bytes.size()) return ParseBinary(bytes, name, summary);
  }
  if (LooksLikeAscii(bytes)) return ParseAscii(bytes, name, summary);
  return ParseBinary(bytes, name, summary);  // reports the size mismatch
}

void WriteStl(std::ostream& out, const TriangleMesh& mesh, const WriteOptions& options) {
  if (mesh.num_faces() > std::numeric_limits<std::uint32_t>::max()) ThrowUsage("too many triangles for STL");
  if (options.binary) {
    WriteBinary(out, mesh, options);
  } else {
    WriteAscii(out, mesh, options);
  }
}

}  // namespace pectus
