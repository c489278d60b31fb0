// Landmark files: CSV (label,x,y,z), and the rows the CSV-like formats (.csv, .fcsv) share.
#include <algorithm>
#include <string>
#include <vector>

#include "shape/io/csv_reader.h"
#include "shape/io/landmark_formats.h"
#include "shape/io/text_scan.h"

namespace pectus::landmark_formats {
std::string QuoteCsv(const std::string& field) {
  const bool plain = field.find_first_of(",\"") == std::string::npos &&
                     (field.empty() || (!text::IsSpace(field.front()) && !text::IsSpace(field.back())));
  if (plain) return field;
  std::string out = "\"";
  for (char c : field) {
    if (c == '"') out += '"';
    out += c;
  }
  return out + "\"";
}

namespace {

double ParseCoordinate(const std::string& field, const char* axis, const Collector& collector,
                       std::int64_t line) {
  double value = 0;
  if (field.empty()) collector.Fail(std::string("missing ") + axis + " coordinate", line);
  if (!text::ParseDouble(field, &value)) {
    collector.Fail("'" + field.substr(0, 40) + "' is not a number (" + axis + " coordinate)", line);
  }
  return value;
}

}  // namespace

int CsvColumns::Needed() const { return std::max({label, x, y, z}) + 1; }

void AddRow(const std::vector<std::string>& fields, const CsvColumns& columns, bool ras, double mm_per_unit,
            Collector* collector, std::int64_t line) {
  if (static_cast<int>(fields.size()) < columns.Needed()) {
    for (int c : {columns.x, columns.y, columns.z}) {
      if (c >= static_cast<int>(fields.size())) collector->Fail("missing coordinate", line);
    }
    collector->Fail("missing label", line);
  }
  const Eigen::Vector3d p(
      ParseCoordinate(fields[static_cast<std::size_t>(columns.x)], "x", *collector, line),
      ParseCoordinate(fields[static_cast<std::size_t>(columns.y)], "y", *collector, line),
      ParseCoordinate(fields[static_cast<std::size_t>(columns.z)], "z", *collector, line));
  const std::string description =
      columns.description >= 0 && columns.description < static_cast<int>(fields.size())
          ? fields[static_cast<std::size_t>(columns.description)]
          : std::string();
  collector->Add(fields[static_cast<std::size_t>(columns.label)], description, p, ras, mm_per_unit, line);
}

std::string OneLine(std::string s) {
  for (char& c : s) {
    if (c == '\n' || c == '\r') c = ' ';
  }
  return s;
}

void AppendXyz(const Eigen::Vector3d& p, std::string* out) {
  for (int k = 0; k < 3; ++k) {
    *out += ',';
    text::AppendNumber(p[k], out);
  }
}

LandmarkSet ParseCsv(std::string_view bytes, const std::string& name, double mm_per_unit) {
  Collector collector(name, "line");
  CsvColumns columns;
  bool first = true;
  CsvReader reader(bytes, name);
  CsvRecord record;
  while (reader.Next(&record)) {
    const std::vector<std::string>& fields = record.fields;
    if (first) {
      first = false;
      // A header names the columns instead of holding numbers in x, y, z.
      double unused = 0;
      bool header = fields.size() >= 4;
      for (std::size_t c = 1; c < 4 && c < fields.size(); ++c)
        header = header && !text::ParseDouble(fields[c], &unused);
      if (header) {
        columns = CsvColumns{-1, -1, -1, -1, -1};
        for (std::size_t c = 0; c < fields.size(); ++c) {
          const std::string column = text::ToLowerAscii(fields[c]);
          const int index = static_cast<int>(c);
          if (column == "label" || column == "name") columns.label = index;
          if (column == "x") columns.x = index;
          if (column == "y") columns.y = index;
          if (column == "z") columns.z = index;
          if (column == "description" || column == "desc") columns.description = index;
        }
        if (columns.label < 0 || columns.x < 0 || columns.y < 0 || columns.z < 0) {
          collector.Fail("the header line must name the columns label, x, y and z", record.line);
        }
        continue;
      }
    }
    AddRow(fields, columns, /*ras=*/false, mm_per_unit, &collector, record.line);
  }
  return collector.Finish();
}

std::string Csv(const LandmarkSet& landmarks) {
  bool descriptions = false;
  for (const Landmark& l : landmarks.items) descriptions = descriptions || !l.description.empty();
  std::string out = descriptions ? "label,x,y,z,description\n" : "label,x,y,z\n";
  for (const Landmark& l : landmarks.items) {
    out += QuoteCsv(l.label);
    AppendXyz(l.position, &out);
    if (descriptions) out += "," + QuoteCsv(OneLine(l.description));
    out += '\n';
  }
  return out;
}

}  // namespace pectus::landmark_formats
