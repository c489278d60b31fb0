// XYZ / CSV point lists: one point per line, an optional header line of column names.
#include <cmath>
#include <cstdint>
#include <set>
#include <string>
#include <vector>

#include "shape/core/error.h"
#include "shape/io/format_parsers.h"
#include "shape/io/text_scan.h"

namespace pectus {
namespace {

constexpr std::size_t kMaxComments = 32;

bool IsSeparator(char c) { return c == ',' || c == ';'; }

// Splits a line into fields. Blanks separate fields and runs of them count once; a comma or semicolon
// (with any blanks around it) is one separator, so "1, 2, 3", "1 2 3" and "1;2;3" all give three fields
// and "1,,3" gives an empty middle field.
void SplitFields(std::string_view line, std::vector<std::string_view>* fields) {
  fields->clear();
  std::size_t i = 0;
  const std::size_t n = line.size();
  const auto skip_blanks = [&] {
    while (i < n && text::IsSpace(line[i])) ++i;
  };
  skip_blanks();
  while (i < n) {
    const std::size_t start = i;
    while (i < n && !text::IsSpace(line[i]) && !IsSeparator(line[i])) ++i;
    fields->push_back(line.substr(start, i - start));
    skip_blanks();
    if (i < n && IsSeparator(line[i])) {
      ++i;
      skip_blanks();
    }
  }
}

std::string_view Unquote(std::string_view s) {
  if (s.size() >= 2 && ((s.front() == '"' && s.back() == '"') || (s.front() == '\'' && s.back() == '\''))) {
    s = s.substr(1, s.size() - 2);
  }
  return s;
}

// What a column holds.
struct Column {
  enum Kind { kPosition, kNormal, kScalar } kind = kScalar;
  int axis = 0;      // 0..2 for positions and normals
  std::string name;  // the scalar's name
};

std::vector<Column> ColumnsFromHeader(const std::vector<std::string_view>& names, const std::string& file,
                                      std::int64_t line) {
  std::vector<Column> columns(names.size());
  std::set<std::string> seen;
  int position_axes = 0, normal_axes = 0;
  for (std::size_t c = 0; c < names.size(); ++c) {
    const std::string name(Unquote(names[c]));
    const std::string lower = text::ToLowerAscii(name);
    if (name.empty())
      ThrowBadInput(file, "column " + std::to_string(c + 1) + " of the header has no name", line);
    if (!seen.insert(lower).second)
      ThrowBadInput(file, "column '" + name + "' appears twice in the header", line);
    Column& column = columns[c];
    for (int axis = 0; axis < 3; ++axis) {
      const std::string a(1, "xyz"[axis]);
      if (lower == a) {
        column.kind = Column::kPosition;
        column.axis = axis;
        ++position_axes;
      } else if (lower == "n" + a || lower == "normal_" + a) {
        column.kind = Column::kNormal;
        column.axis = axis;
        ++normal_axes;
      }
    }
    if (column.kind == Column::kScalar) column.name = name;
  }
  if (position_axes != 3) ThrowBadInput(file, "the header line does not name the x, y and z columns", line);
  if (normal_axes != 0 && normal_axes != 3) {
    ThrowBadInput(file, "the header names some but not all of the normal columns nx, ny, nz", line);
  }
  return columns;
}

// Without a header: 3 columns are x y z, 6 are x y z nx ny nz, otherwise x y z and scalars s3, s4, ...
std::vector<Column> ColumnsByCount(std::size_t count, const std::string& file, std::int64_t line) {
  if (count < 3) {
    ThrowBadInput(file, "a point needs at least 3 columns (x y z); this line has " + std::to_string(count),
                  line);
  }
  std::vector<Column> columns(count);
  for (std::size_t c = 0; c < count; ++c) {
    if (c < 3) {
      columns[c] = {Column::kPosition, static_cast<int>(c), {}};
    } else if (count == 6) {
      columns[c] = {Column::kNormal, static_cast<int>(c - 3), {}};
    } else {
      columns[c] = {Column::kScalar, 0, std::string("s").append(std::to_string(c))};
    }
  }
  return columns;
}

void Flush(std::string* buffer, std::ostream& out) {
  out.write(buffer->data(), static_cast<std::streamsize>(buffer->size()));
  buffer->clear();
}

}  // namespace

TriangleMesh ParseXyz(std::string_view bytes, const std::string& name, FileSummary* summary) {
  text::LineReader lines(text::StripBom(bytes));
  std::vector<std::string_view> fields;
  std::vector<Column> columns;
  std::vector<std::string> comments;
  std::vector<double> values;  // #points x #columns, row-major
  std::string_view line;
  while (lines.Next(&line)) {
    const std::string_view trimmed = text::Trim(line);
    if (trimmed.empty()) continue;
    if (trimmed.front() == '#') {
      if (comments.size() < kMaxComments) comments.emplace_back(text::Trim(trimmed.substr(1)));
      continue;
    }
    SplitFields(trimmed, &fields);
    if (columns.empty()) {
      // The first line is a header if any of its (non-empty) fields is not a number.
      bool header = false;
      double unused = 0;
      for (std::string_view f : fields) header = header || (!f.empty() && !text::ParseDouble(f, &unused));
      if (header) {
        columns = ColumnsFromHeader(fields, name, lines.number());
        continue;
      }
      columns = ColumnsByCount(fields.size(), name, lines.number());
    }
    if (fields.size() != columns.size()) {
      ThrowBadInput(name,
                    "this line has " + std::to_string(fields.size()) +
                        " columns but the file's first line has " + std::to_string(columns.size()),
                    lines.number());
    }
    for (std::size_t c = 0; c < fields.size(); ++c) {
      const std::string_view f = fields[c];
      double value = 0;
      if (f.empty()) ThrowBadInput(name, "column " + std::to_string(c + 1) + " is empty", lines.number());
      if (!text::ParseDouble(f, &value)) {
        ThrowBadInput(name, "'" + std::string(f.substr(0, 40)) + "' is not a number", lines.number());
      }
      // Scalars may be NaN ("no value"); coordinates and normals may not.
      if (!std::isfinite(value) && columns[c].kind != Column::kScalar) {
        ThrowBadInput(name, "non-finite coordinate '" + std::string(f) + "' (NaN or Inf)", lines.number());
      }
      values.push_back(value);
    }
  }
  if (columns.empty()) ThrowBadInput(name, "no points in the file");

  const std::size_t num_columns = columns.size();
  const auto n = static_cast<Eigen::Index>(values.size() / num_columns);
  TriangleMesh mesh;
  PointCloud& cloud = mesh.vertices;
  cloud.positions.resize(n, 3);
  bool has_normals = false;
  for (const Column& c : columns) has_normals = has_normals || c.kind == Column::kNormal;
  if (has_normals) cloud.normals.resize(n, 3);
  for (std::size_t c = 0; c < num_columns; ++c) {
    const Column& column = columns[c];
    Eigen::VectorXd scalar;
    if (column.kind == Column::kScalar) scalar.resize(n);
    for (Eigen::Index i = 0; i < n; ++i) {
      const double v = values[static_cast<std::size_t>(i) * num_columns + c];
      switch (column.kind) {
        case Column::kPosition: cloud.positions(i, column.axis) = v; break;
        case Column::kNormal: cloud.normals(i, column.axis) = v; break;
        case Column::kScalar: scalar[i] = v; break;
      }
    }
    if (column.kind == Column::kScalar) cloud.scalars[column.name] = std::move(scalar);
  }
  mesh.faces.resize(0, 3);

  if (summary) {
    *summary = FileSummary{};
    summary->format = text::EndsWithNoCase(name, ".csv") ? "csv" : "xyz";
    summary->encoding = "ascii";
    ElementSummary vertex{"vertex", n, {}};
    for (const Column& c : columns) {
      const std::string axis(1, "xyz"[c.axis]);
      vertex.properties.push_back(c.kind == Column::kPosition ? axis
                                  : c.kind == Column::kNormal ? "n" + axis
                                                              : c.name);
    }
    summary->elements.push_back(std::move(vertex));
    summary->comments = std::move(comments);
  }
  return mesh;
}

void WriteXyz(std::ostream& out, const TriangleMesh& mesh, char separator, const WriteOptions& options) {
  const PointCloud& cloud = mesh.vertices;
  const bool csv = separator == ',';
  std::string buffer;
  buffer.reserve(1 << 20);
  if (csv) {
    // CSV: a header line names the columns, so scalars can go along.
    buffer += "x,y,z";
    if (cloud.has_normals()) buffer += ",nx,ny,nz";
    for (const auto& [scalar, values] : cloud.scalars) buffer += "," + scalar;
    buffer += '\n';
  } else if (!options.comment.empty()) {
    text::LineReader comment(options.comment);
    std::string_view line;
    while (comment.Next(&line)) buffer.append("# ").append(line).append("\n");
  }
  for (Eigen::Index i = 0; i < cloud.size(); ++i) {
    for (int k = 0; k < 3; ++k) {
      if (k > 0) buffer += separator;
      text::AppendNumber(cloud.positions(i, k), &buffer);
    }
    if (cloud.has_normals()) {
      for (int k = 0; k < 3; ++k) {
        buffer += separator;
        text::AppendNumber(cloud.normals(i, k), &buffer);
      }
    }
    if (csv) {
      for (const auto& [scalar, values] : cloud.scalars) {
        buffer += separator;
        text::AppendNumber(values[i], &buffer);
      }
    }
    buffer += '\n';
    if (buffer.size() > (1 << 20) - 4096) Flush(&buffer, out);
  }
  Flush(&buffer, out);
}

}  // namespace pectus
