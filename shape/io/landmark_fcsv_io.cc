// Landmark files: legacy 3D Slicer fiducial lists (.fcsv).
#include <string>
#include <vector>

#include "shape/io/csv_reader.h"
#include "shape/io/landmark_formats.h"
#include "shape/io/text_scan.h"

namespace pectus::landmark_formats {
namespace {

constexpr const char* kFcsvColumns = "id,x,y,z,ow,ox,oy,oz,vis,sel,lock,label,desc,associatedNodeID";

}  // namespace

LandmarkSet ParseFcsv(std::string_view bytes, const std::string& name, double mm_per_unit) {
  Collector collector(name, "line");
  bool ras = true;  // Slicer's default; files older than 4.11 have no CoordinateSystem line
  CsvColumns columns{11, 1, 2, 3, 12};
  CsvReader reader(bytes, name, CsvReadOptions{.return_comments = true});
  CsvRecord record;
  while (reader.Next(&record)) {
    if (record.is_comment) {
      const std::string_view comment = text::Trim(record.comment);
      const std::size_t eq = comment.find('=');
      if (eq == std::string_view::npos) continue;
      const std::string key = text::ToLowerAscii(text::Trim(comment.substr(0, eq)));
      const std::string_view value = text::Trim(comment.substr(eq + 1));
      if (key == "coordinatesystem") {
        if (value == "RAS" || value == "0") {
          ras = true;
        } else if (value == "LPS" || value == "1") {
          ras = false;
        } else {
          collector.Fail("unknown CoordinateSystem '" + std::string(value) + "' (expected RAS, LPS, 0 or 1)",
                         record.line);
        }
      } else if (key == "columns") {
        const std::vector<std::string> fields = SplitCsvLine(value, name, record.line);
        columns = CsvColumns{-1, -1, -1, -1, -1};
        for (std::size_t c = 0; c < fields.size(); ++c) {
          const std::string column = text::ToLowerAscii(fields[c]);
          const int index = static_cast<int>(c);
          if (column == "label") columns.label = index;
          if (column == "x") columns.x = index;
          if (column == "y") columns.y = index;
          if (column == "z") columns.z = index;
          if (column == "desc") columns.description = index;
        }
        if (columns.label < 0 || columns.x < 0 || columns.y < 0 || columns.z < 0) {
          collector.Fail("the columns line lacks one of label, x, y, z", record.line);
        }
      }
      continue;
    }
    AddRow(record.fields, columns, ras, mm_per_unit, &collector, record.line);
  }
  return collector.Finish();
}

std::string Fcsv(const LandmarkSet& landmarks) {
  std::string out = "# Markups fiducial file version = 4.11\n# CoordinateSystem = LPS\n# columns = ";
  out += kFcsvColumns;
  out += '\n';
  for (std::size_t i = 0; i < landmarks.items.size(); ++i) {
    const Landmark& l = landmarks.items[i];
    out += std::to_string(i + 1);
    AppendXyz(l.position, &out);
    out += ",0,0,0,1,1,1,0," + QuoteCsv(l.label) + "," + QuoteCsv(OneLine(l.description)) + ",\n";
  }
  return out;
}

}  // namespace pectus::landmark_formats
