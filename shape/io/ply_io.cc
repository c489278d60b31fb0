// pectus: PLY reader and writer (ASCII, binary little endian, binary big endian). The reader's parts are
// ply_header.cc (header, property mapping), ply_ascii.cc and ply_binary.cc (the data); ply_format.h says
// how they fit together.
#include <charconv>
#include <limits>
#include <memory>

#include "shape/core/error.h"
#include "shape/io/format_parsers.h"
#include "shape/io/ply_format.h"

namespace pectus {
namespace {

std::string ScalarPropertyName(const std::string& scalar) {
  std::string out = scalar.empty() ? std::string("scalar") : scalar;
  for (char& c : out) {
    if (ply::IsBlank(c) || c == '\n') c = '_';
  }
  static const char* const kReserved[] = {
      "x", "y", "z", "nx", "ny", "nz", "red", "green", "blue", "alpha", "vertex_indices"};
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
  const ply::Header header = ply::ParseHeader(bytes, name, summary);

  // Which elements hold the vertices and the faces.
  const ply::Element* vertex = nullptr;
  const ply::Element* face = nullptr;
  int index_property = -1;
  for (const ply::Element& e : header.elements) {
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
    if (!ply::IsInteger(face->properties[index_property].type)) {
      ThrowBadInput(name, "the face indices must have an integer type", face->header_line);
    }
  }

  TriangleMesh mesh;
  Faces3 faces;
  const std::string_view data = bytes.substr(header.data_offset);
  const ply::Layout layout{vertex, face, index_property};
  if (header.encoding == ply::Encoding::kAscii) {
    ply::ReadAsciiData(data, header, layout, name, &mesh, &faces);
  } else {
    ply::ReadBinaryData(data, header, layout, name, &mesh, &faces);
  }
  if (faces.rows() == 0) faces.resize(0, 3);
  mesh.faces = std::move(faces);
  return mesh;
}

void WritePly(std::ostream& out, const TriangleMesh& mesh, const WriteOptions& options) {
  const PointCloud& cloud = mesh.vertices;
  const Eigen::Index n = cloud.size();
  if (cloud.has_normals() && cloud.normals.rows() != n)
    ThrowUsage("PLY writer: normals and positions differ in count");
  if (cloud.has_colors() && cloud.colors.rows() != n)
    ThrowUsage("PLY writer: colours and positions differ in count");
  std::vector<std::string> scalar_names;
  std::vector<const double*> scalar_values;
  for (const auto& [scalar_name, values] : cloud.scalars) {
    if (values.size() != n)
      ThrowUsage("PLY writer: scalar '" + scalar_name + "' and positions differ in count");
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
  for (const char* axis : {"x", "y", "z"})
    header += std::string("property ") + position_type + " " + axis + "\n";
  if (normals) header += "property float nx\nproperty float ny\nproperty float nz\n";
  if (colors) header += "property uchar red\nproperty uchar green\nproperty uchar blue\n";
  for (const std::string& s : scalar_names) header += "property float " + s + "\n";
  if (num_faces > 0)
    header += "element face " + std::to_string(num_faces) + "\nproperty list uchar int vertex_indices\n";
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
        wide ? ply::StoreLittleEndian(r, pos[3 * i + k])
             : ply::StoreLittleEndian(r, static_cast<float>(pos[3 * i + k]));
      }
      if (normals) {
        for (int k = 0; k < 3; ++k, r += 4) ply::StoreLittleEndian(r, static_cast<float>(nrm[3 * i + k]));
      }
      if (colors) {
        std::memcpy(r, rgb + 3 * i, 3);
        r += 3;
      }
      for (const double* values : scalar_values) {
        ply::StoreLittleEndian(r, static_cast<float>(values[i]));
        r += 4;
      }
    }
    out.write(buffer.get(), static_cast<std::streamsize>(vertex_bytes));
    r = buffer.get();
    for (Eigen::Index f = 0; f < num_faces; ++f, r += 13) {
      r[0] = 3;
      for (int k = 0; k < 3; ++k) ply::StoreLittleEndian(r + 1 + 4 * k, tri[3 * f + k]);
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
