// Wavefront OBJ reader and writer (geometry only: v, vn, f; materials and texture coordinates ignored).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "shape/core/error.h"
#include "shape/io/format_parsers.h"
#include "shape/io/text_scan.h"

namespace pectus {
namespace {

constexpr std::size_t kMaxComments = 32;

// Keywords of the OBJ specification that carry nothing pectus uses.
bool IsIgnoredKeyword(std::string_view k) {
  for (std::string_view known :
       {"vt",       "vp",       "g",          "o",         "s",      "usemtl", "mtllib", "l",    "p",
        "mg",       "lod",      "usemap",     "maplib",    "cstype", "deg",    "bmat",   "step", "curv",
        "curv2",    "surf",     "parm",       "trim",      "hole",   "scrv",   "sp",     "end",  "con",
        "c_interp", "d_interp", "shadow_obj", "trace_obj", "bevel",  "call",   "csh"}) {
    if (k == known) return true;
  }
  // Vendor extensions are words too; anything else (binary data, a stray number) is an error.
  for (char c : k) {
    if (!((c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_'))
      return false;
  }
  return !k.empty() && !(k[0] >= '0' && k[0] <= '9');
}

class ObjParser {
 public:
  ObjParser(std::string_view bytes, const std::string& name) : lines_(bytes), name_(name) {}

  TriangleMesh Parse(FileSummary* summary);

 private:
  [[noreturn]] void Fail(const std::string& message) const { ThrowBadInput(name_, message, lines_.number()); }
  // Reads up to `max` numbers of the rest of a line into `out`; returns how many there were.
  int ReadNumbers(std::string_view rest, double* out, int max, const char* what);
  // Resolves a 1-based (or negative, relative) index against `defined` items so far; 0-based result.
  std::int64_t ResolveIndex(std::string_view token, std::int64_t defined, const char* what,
                            std::int64_t* max_ref, std::int64_t* max_ref_line);
  void ParseFace(std::string_view rest);
  void CheckForwardReference(std::int64_t max_ref, std::int64_t line, std::int64_t defined, const char* what);
  Points3 VertexNormals(Eigen::Index num_vertices) const;

  text::LineReader lines_;
  const std::string& name_;
  std::vector<double> positions_, colors_, normals_;  // 3 per item
  std::int64_t num_colored_ = 0;
  std::int64_t num_polygons_ = 0, num_texcoords_ = 0;
  std::vector<std::int64_t> corner_vertex_, corner_normal_;  // 3 per triangle; normal -1 if none
  std::int64_t max_vertex_ref_ = -1, max_vertex_line_ = 0, max_normal_ref_ = -1, max_normal_line_ = 0;
  std::vector<std::int64_t> polygon_v_, polygon_n_;  // scratch for one face line
  std::vector<std::string> comments_;
};

int ObjParser::ReadNumbers(std::string_view rest, double* out, int max, const char* what) {
  int n = 0;
  for (std::string_view token = text::NextToken(&rest); !token.empty(); token = text::NextToken(&rest)) {
    if (n == max) Fail(std::string("too many numbers on a '") + what + "' line");
    double value = 0;
    if (!text::ParseDouble(token, &value)) Fail(text::Quoted(token) + " is not a number");
    if (!std::isfinite(value)) Fail("non-finite number " + text::Quoted(token) + " (NaN or Inf)");
    out[n++] = value;
  }
  return n;
}

std::int64_t ObjParser::ResolveIndex(std::string_view token, std::int64_t defined, const char* what,
                                     std::int64_t* max_ref, std::int64_t* max_ref_line) {
  std::int64_t index = 0;
  if (!text::ParseInt(token, &index)) Fail(text::Quoted(token) + " is not a " + what + " index");
  if (index == 0) Fail(std::string(what) + " index 0 (OBJ indices start at 1)");
  if (index < 0) {
    // Relative: -1 is the last one defined so far.
    if (index < -defined) {
      Fail(std::string(what) + " index " + std::to_string(index) + " out of range: only " +
           std::to_string(defined) + " " + what + "s defined before this line");
    }
    return defined + index;
  }
  // Positive indices may in principle refer forward; they are checked once the whole file is read.
  if (index - 1 > *max_ref) {
    *max_ref = index - 1;
    *max_ref_line = lines_.number();
  }
  return index - 1;
}

void ObjParser::ParseFace(std::string_view rest) {
  polygon_v_.clear();
  polygon_n_.clear();
  const auto num_vertices = static_cast<std::int64_t>(positions_.size() / 3);
  const auto num_normals = static_cast<std::int64_t>(normals_.size() / 3);
  for (std::string_view token = text::NextToken(&rest); !token.empty(); token = text::NextToken(&rest)) {
    // v, v/vt, v//vn or v/vt/vn.
    const std::size_t slash1 = token.find('/');
    const std::string_view v = token.substr(0, slash1);
    std::int64_t n = -1;
    if (slash1 != std::string_view::npos) {
      const std::size_t slash2 = token.find('/', slash1 + 1);
      if (slash2 != std::string_view::npos && slash2 + 1 < token.size()) {
        n = ResolveIndex(token.substr(slash2 + 1), num_normals, "normal", &max_normal_ref_,
                         &max_normal_line_);
      }
    }
    polygon_v_.push_back(ResolveIndex(v, num_vertices, "vertex", &max_vertex_ref_, &max_vertex_line_));
    polygon_n_.push_back(n);
  }
  if (polygon_v_.size() < 3) {
    Fail("face with " + std::to_string(polygon_v_.size()) + " vertices (a face needs at least 3)");
  }
  ++num_polygons_;
  // Fan: (0, i, i+1).
  for (std::size_t i = 1; i + 1 < polygon_v_.size(); ++i) {
    for (std::size_t k : {std::size_t{0}, i, i + 1}) {
      corner_vertex_.push_back(polygon_v_[k]);
      corner_normal_.push_back(polygon_n_[k]);
    }
  }
}

void ObjParser::CheckForwardReference(std::int64_t max_ref, std::int64_t line, std::int64_t defined,
                                      const char* what) {
  if (max_ref >= defined) {
    ThrowBadInput(name_,
                  std::string(what) + " index " + std::to_string(max_ref + 1) +
                      " out of range: the file has " + std::to_string(defined) + " " + what + "s",
                  line);
  }
}

// OBJ normals belong to face corners. They become vertex normals when every vertex gets one normal (the
// case for smooth meshes and for files pectus writes); otherwise (flat shading, creases) they are dropped.
Points3 ObjParser::VertexNormals(Eigen::Index num_vertices) const {
  const auto num_normals = static_cast<std::int64_t>(normals_.size() / 3);
  Points3 result(0, 3);
  if (num_normals == 0) return result;
  const auto same = [&](std::int64_t a, std::int64_t b) {
    return normals_[3 * a] == normals_[3 * b] && normals_[3 * a + 1] == normals_[3 * b + 1] &&
           normals_[3 * a + 2] == normals_[3 * b + 2];
  };
  std::vector<std::int64_t> normal_of(static_cast<std::size_t>(num_vertices), -1);
  for (std::size_t c = 0; c < corner_vertex_.size(); ++c) {
    const std::int64_t n = corner_normal_[c];
    if (n < 0) return result;  // a corner without a normal
    std::int64_t& assigned = normal_of[static_cast<std::size_t>(corner_vertex_[c])];
    if (assigned < 0) {
      assigned = n;
    } else if (assigned != n && !same(assigned, n)) {
      return result;  // two different normals at one vertex
    }
  }
  // Vertices no face uses (or a point cloud): the i-th normal, when there is one per vertex.
  for (Eigen::Index v = 0; v < num_vertices; ++v) {
    std::int64_t& assigned = normal_of[static_cast<std::size_t>(v)];
    if (assigned >= 0) continue;
    if (num_normals != num_vertices) return result;
    assigned = v;
  }
  result.resize(num_vertices, 3);
  for (Eigen::Index v = 0; v < num_vertices; ++v) {
    const std::int64_t n = normal_of[static_cast<std::size_t>(v)];
    result.row(v) << normals_[3 * n], normals_[3 * n + 1], normals_[3 * n + 2];
  }
  return result;
}

TriangleMesh ObjParser::Parse(FileSummary* summary) {
  std::string_view line;
  double numbers[6];
  while (lines_.Next(&line)) {
    std::string_view rest = line;
    const std::string_view keyword = text::NextToken(&rest);
    if (keyword.empty()) continue;
    if (keyword[0] == '#') {
      if (summary && comments_.size() < kMaxComments) {
        comments_.emplace_back(text::Trim(text::Trim(line).substr(1)));
      }
      continue;
    }
    if (keyword == "v") {
      const int n = ReadNumbers(rest, numbers, 6, "v");
      if (n != 3 && n != 4 && n != 6) {
        Fail("a vertex needs x y z (optionally w, or r g b colours); got " + std::to_string(n) + " numbers");
      }
      positions_.insert(positions_.end(), numbers, numbers + 3);
      if (n == 6) {
        // Colour extension: r g b in 0..1 after the position.
        colors_.resize(positions_.size() - 3, 0.0);
        colors_.insert(colors_.end(), numbers + 3, numbers + 6);
        ++num_colored_;
      }
    } else if (keyword == "vn") {
      if (ReadNumbers(rest, numbers, 3, "vn") != 3) Fail("a normal (vn) needs 3 numbers");
      normals_.insert(normals_.end(), numbers, numbers + 3);
    } else if (keyword == "f") {
      ParseFace(rest);
    } else if (keyword == "vt") {
      ++num_texcoords_;
    } else if (!IsIgnoredKeyword(keyword)) {
      Fail("unexpected " + text::Quoted(keyword) + " (not an OBJ keyword)");
    }
  }

  const auto num_vertices = static_cast<std::int64_t>(positions_.size() / 3);
  if (num_vertices == 0) ThrowBadInput(name_, "no vertices (no 'v' lines): not an OBJ file?");
  if (num_vertices > std::numeric_limits<std::int32_t>::max()) ThrowBadInput(name_, "too many vertices");
  CheckForwardReference(max_vertex_ref_, max_vertex_line_, num_vertices, "vertex");
  CheckForwardReference(max_normal_ref_, max_normal_line_, static_cast<std::int64_t>(normals_.size() / 3),
                        "normal");

  TriangleMesh mesh;
  mesh.vertices.positions = Eigen::Map<const Points3>(positions_.data(), num_vertices, 3);
  if (num_colored_ == num_vertices) {
    mesh.vertices.colors.resize(num_vertices, 3);
    for (std::int64_t i = 0; i < 3 * num_vertices; ++i) {
      const double c = std::clamp(colors_[static_cast<std::size_t>(i)], 0.0, 1.0);
      mesh.vertices.colors.data()[i] = static_cast<std::uint8_t>(std::lround(c * 255.0));
    }
  }
  const auto num_triangles = static_cast<Eigen::Index>(corner_vertex_.size() / 3);
  mesh.faces.resize(num_triangles, 3);
  for (std::size_t c = 0; c < corner_vertex_.size(); ++c) {
    mesh.faces.data()[c] = static_cast<std::int32_t>(corner_vertex_[c]);
  }
  mesh.vertices.normals = VertexNormals(num_vertices);

  if (summary) {
    *summary = FileSummary{};
    summary->format = "obj";
    summary->encoding = "ascii";
    ElementSummary vertex{"vertex", num_vertices, {"x", "y", "z"}};
    if (num_colored_ == num_vertices)
      vertex.properties.insert(vertex.properties.end(), {"red", "green", "blue"});
    summary->elements.push_back(vertex);
    if (!normals_.empty()) {
      summary->elements.push_back(
          {"normal", static_cast<std::int64_t>(normals_.size() / 3), {"nx", "ny", "nz"}});
    }
    if (num_texcoords_ > 0) summary->elements.push_back({"texcoord", num_texcoords_, {"u", "v"}});
    summary->elements.push_back({"face", num_polygons_, {"vertex_indices"}});
    summary->comments = std::move(comments_);
  }
  return mesh;
}

void Flush(std::string* buffer, std::ostream& out) {
  out.write(buffer->data(), static_cast<std::streamsize>(buffer->size()));
  buffer->clear();
}

}  // namespace

TriangleMesh ParseObj(std::string_view bytes, const std::string& name, FileSummary* summary) {
  return ObjParser(bytes, name).Parse(summary);
}

void WriteObj(std::ostream& out, const TriangleMesh& mesh, const WriteOptions& options) {
  const PointCloud& v = mesh.vertices;
  const bool normals = v.has_normals();
  const bool colors = v.has_colors();
  std::string buffer;
  buffer.reserve(1 << 20);
  buffer += "# written by pectus\n";
  if (!options.comment.empty()) {
    text::LineReader comment(options.comment);
    std::string_view line;
    while (comment.Next(&line)) buffer.append("# ").append(line).append("\n");
  }
  for (Eigen::Index i = 0; i < v.size(); ++i) {
    buffer += "v";
    for (int k = 0; k < 3; ++k) {
      buffer += ' ';
      text::AppendNumber(v.positions(i, k), &buffer);
    }
    if (colors) {
      for (int k = 0; k < 3; ++k) {
        buffer += ' ';
        text::AppendNumber(v.colors(i, k) / 255.0, &buffer);
      }
    }
    buffer += '\n';
    if (buffer.size() > (1 << 20) - 256) Flush(&buffer, out);
  }
  if (normals) {
    for (Eigen::Index i = 0; i < v.size(); ++i) {
      buffer += "vn";
      for (int k = 0; k < 3; ++k) {
        buffer += ' ';
        text::AppendNumber(v.normals(i, k), &buffer);
      }
      buffer += '\n';
      if (buffer.size() > (1 << 20) - 256) Flush(&buffer, out);
    }
  }
  for (Eigen::Index f = 0; f < mesh.num_faces(); ++f) {
    buffer += 'f';
    for (int k = 0; k < 3; ++k) {
      buffer += ' ';
      const std::int64_t index = std::int64_t{mesh.faces(f, k)} + 1;
      text::AppendInt(index, &buffer);
      if (normals) {
        buffer += "//";
        text::AppendInt(index, &buffer);
      }
    }
    buffer += '\n';
    if (buffer.size() > (1 << 20) - 256) Flush(&buffer, out);
  }
  Flush(&buffer, out);
}

}  // namespace pectus
