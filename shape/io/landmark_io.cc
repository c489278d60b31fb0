// Landmark files: 3D Slicer markups (.mrk.json), legacy Slicer fiducial lists (.fcsv) and CSV.
#include "shape/io/landmark_io.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "shape/core/atomic_file.h"
#include "shape/core/error.h"
#include "shape/io/mapped_file.h"
#include "shape/io/text_scan.h"

namespace pectus {
namespace {

enum class LandmarkFormat { kMarkupsJson, kFcsv, kCsv };

LandmarkFormat FormatOf(const std::string& name) {
  if (text::EndsWithNoCase(name, ".json")) return LandmarkFormat::kMarkupsJson;
  if (text::EndsWithNoCase(name, ".fcsv")) return LandmarkFormat::kFcsv;
  if (text::EndsWithNoCase(name, ".csv")) return LandmarkFormat::kCsv;
  ThrowUsage(name + ": unknown landmark file type (pectus reads and writes .mrk.json, .fcsv and .csv)");
}

constexpr const char* kMarkupsSchema =
    "https://raw.githubusercontent.com/slicer/slicer/master/Modules/Loadable/Markups/Resources/Schema/"
    "markups-schema-v1.0.3.json#";
constexpr const char* kFcsvColumns = "id,x,y,z,ow,ox,oy,oz,vis,sel,lock,label,desc,associatedNodeID";

// Gathers landmarks from any format: converts RAS to LPS and units to mm, and rejects empty, invalid
// UTF-8 or duplicate labels and non-finite positions, naming the line (or control point) at fault.
class Collector {
 public:
  Collector(const std::string& name, const char* item_word) : name_(name), item_word_(item_word) {}

  // `item` is the line number (text formats) or the control point number (JSON).
  void Add(const std::string& label, const std::string& description, Eigen::Vector3d position, bool ras,
           double mm_per_unit, std::int64_t item) {
    if (label.empty()) Fail("missing label", item);
    if (!text::IsValidUtf8(label)) Fail("label is not valid UTF-8 text", item);
    if (!text::IsValidUtf8(description)) Fail("description is not valid UTF-8 text", item);
    if (!position.allFinite())
      Fail("landmark '" + label + "' has a non-finite coordinate (NaN or Inf)", item);
    const auto [it, inserted] = first_item_.try_emplace(label, item);
    if (!inserted) {
      Fail("duplicate landmark label '" + label + "' (" + item_word_ + "s " + std::to_string(it->second) +
               " and " + std::to_string(item) + ")",
           item);
    }
    if (ras) {
      position.x() = -position.x();
      position.y() = -position.y();
    }
    set_.items.push_back({label, position * mm_per_unit, description});
  }

  [[noreturn]] void Fail(const std::string& message, std::int64_t item) const {
    if (item_word_ == "line") ThrowBadInput(name_, message, item);
    ThrowBadInput(name_, item_word_ + " " + std::to_string(item) + ": " + message);
  }

  LandmarkSet Finish() {
    if (set_.items.empty()) ThrowBadInput(name_, "no landmarks in the file");
    return std::move(set_);
  }

 private:
  const std::string& name_;
  std::string item_word_;
  std::map<std::string, std::int64_t> first_item_;
  LandmarkSet set_;
};

// ---- CSV fields ----

// Splits one CSV line into fields. A field in double quotes may hold commas, and "" stands for one quote.
// Unquoted fields are trimmed. Returns false (with `why`) for an unterminated quote.
bool SplitCsv(std::string_view line, std::vector<std::string>* fields, std::string* why) {
  fields->clear();
  std::size_t i = 0;
  while (true) {
    while (i < line.size() && text::IsSpace(line[i])) ++i;
    std::string field;
    if (i < line.size() && line[i] == '"') {
      ++i;
      bool closed = false;
      while (i < line.size()) {
        if (line[i] == '"') {
          if (i + 1 < line.size() && line[i + 1] == '"') {
            field += '"';
            i += 2;
            continue;
          }
          ++i;
          closed = true;
          break;
        }
        field += line[i++];
      }
      if (!closed) {
        *why = "unterminated quoted field";
        return false;
      }
      while (i < line.size() && text::IsSpace(line[i])) ++i;
      if (i < line.size() && line[i] != ',') {
        *why = "text after a closing quote";
        return false;
      }
    } else {
      const std::size_t start = i;
      while (i < line.size() && line[i] != ',') ++i;
      field = std::string(text::Trim(line.substr(start, i - start)));
    }
    fields->push_back(std::move(field));
    if (i >= line.size()) return true;
    ++i;  // the comma
  }
}

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

double ParseCoordinate(const std::string& field, const char* axis, const Collector& collector,
                       std::int64_t line) {
  double value = 0;
  if (field.empty()) collector.Fail(std::string("missing ") + axis + " coordinate", line);
  if (!text::ParseDouble(field, &value)) {
    collector.Fail("'" + field.substr(0, 40) + "' is not a number (" + axis + " coordinate)", line);
  }
  return value;
}

// Column positions of a CSV-like table.
struct CsvColumns {
  int label = 0, x = 1, y = 2, z = 3, description = 4;
  int Needed() const { return std::max({label, x, y, z}) + 1; }
};

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

// ---- .fcsv ----

LandmarkSet ParseFcsv(std::string_view bytes, const std::string& name, double mm_per_unit) {
  Collector collector(name, "line");
  bool ras = true;  // Slicer's default; files older than 4.11 have no CoordinateSystem line
  CsvColumns columns{11, 1, 2, 3, 12};
  text::LineReader lines(bytes);
  std::vector<std::string> fields;
  std::string why;
  std::string_view line;
  while (lines.Next(&line)) {
    const std::string_view trimmed = text::Trim(line);
    if (trimmed.empty()) continue;
    if (trimmed.front() == '#') {
      const std::string_view comment = text::Trim(trimmed.substr(1));
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
                         lines.number());
        }
      } else if (key == "columns") {
        if (!SplitCsv(value, &fields, &why)) collector.Fail(why, lines.number());
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
          collector.Fail("the columns line lacks one of label, x, y, z", lines.number());
        }
      }
      continue;
    }
    if (!SplitCsv(trimmed, &fields, &why)) collector.Fail(why, lines.number());
    AddRow(fields, columns, ras, mm_per_unit, &collector, lines.number());
  }
  return collector.Finish();
}

// ---- .csv ----

LandmarkSet ParseCsv(std::string_view bytes, const std::string& name, double mm_per_unit) {
  Collector collector(name, "line");
  CsvColumns columns;
  bool first = true;
  text::LineReader lines(bytes);
  std::vector<std::string> fields;
  std::string why;
  std::string_view line;
  while (lines.Next(&line)) {
    const std::string_view trimmed = text::Trim(line);
    if (trimmed.empty() || trimmed.front() == '#') continue;
    if (!SplitCsv(trimmed, &fields, &why)) collector.Fail(why, lines.number());
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
          collector.Fail("the header line must name the columns label, x, y and z", lines.number());
        }
        continue;
      }
    }
    AddRow(fields, columns, /*ras=*/false, mm_per_unit, &collector, lines.number());
  }
  return collector.Finish();
}

// ---- .mrk.json ----

std::string JsonErrorText(const nlohmann::json::exception& e) {
  // "[json.exception.parse_error.101] parse error at line 3, column 5: ..." without the bracketed id.
  std::string what = e.what();
  const std::size_t close = what.find("] ");
  return close == std::string::npos ? what : what.substr(close + 2);
}

LandmarkSet ParseMarkupsJson(std::string_view bytes, const std::string& name, double default_mm_per_unit) {
  nlohmann::json root;
  try {
    root = nlohmann::json::parse(bytes.begin(), bytes.end());
  } catch (const nlohmann::json::exception& e) {  // parse_error, or out_of_range for 1e999
    ThrowBadInput(name, "malformed JSON: " + JsonErrorText(e));
  }
  if (!root.is_object() || !root.contains("markups") || !root["markups"].is_array()) {
    ThrowBadInput(name, "not a Slicer markups file (no \"markups\" list)");
  }
  Collector collector(name, "control point");
  std::int64_t item = 0;  // control points numbered across all markups, from 1
  const nlohmann::json& markups = root["markups"];
  for (std::size_t m = 0; m < markups.size(); ++m) {
    const nlohmann::json& markup = markups[m];
    const std::string where = "markup " + std::to_string(m + 1);
    if (!markup.is_object()) ThrowBadInput(name, where + " is not a JSON object");
    if (markup.value("type", std::string()) != "Fiducial") continue;  // lines, curves, planes, ...
    bool ras = false;                                                 // the schema's default is LPS
    if (markup.contains("coordinateSystem")) {
      const nlohmann::json& system = markup["coordinateSystem"];
      if (system == "RAS") {
        ras = true;
      } else if (system != "LPS") {
        ThrowBadInput(
            name, where + ": unknown coordinateSystem " + system.dump() + " (expected \"LPS\" or \"RAS\")");
      }
    }
    double mm_per_unit = default_mm_per_unit;
    if (markup.contains("coordinateUnits")) {
      const nlohmann::json& units = markup["coordinateUnits"];
      if (units == "mm") {
        mm_per_unit = 1.0;
      } else if (units == "m") {
        mm_per_unit = 1000.0;
      } else {
        ThrowBadInput(name,
                      where + ": unknown coordinateUnits " + units.dump() + " (expected \"mm\" or \"m\")");
      }
    }
    if (!markup.contains("controlPoints")) continue;
    const nlohmann::json& points = markup["controlPoints"];
    if (!points.is_array()) ThrowBadInput(name, where + ": \"controlPoints\" is not a list");
    for (const nlohmann::json& point : points) {
      ++item;
      if (!point.is_object()) collector.Fail("not a JSON object", item);
      if (point.contains("positionStatus") && point["positionStatus"] != "defined")
        continue;  // not yet placed
      std::string label, description;
      if (point.contains("label")) {
        if (!point["label"].is_string()) collector.Fail("label is not a string", item);
        label = point["label"].get<std::string>();
      }
      if (point.contains("description") && point["description"].is_string()) {
        description = point["description"].get<std::string>();
      }
      if (!point.contains("position")) collector.Fail("missing coordinate (no \"position\")", item);
      const nlohmann::json& position = point["position"];
      if (!position.is_array() || position.size() != 3) {
        collector.Fail("missing coordinate (\"position\" must be a list of 3 numbers)", item);
      }
      Eigen::Vector3d p;
      for (int k = 0; k < 3; ++k) {
        if (!position[static_cast<std::size_t>(k)].is_number()) {
          collector.Fail("coordinate " + position[static_cast<std::size_t>(k)].dump() + " is not a number",
                         item);
        }
        p[k] = position[static_cast<std::size_t>(k)].get<double>();
      }
      collector.Add(label, description, p, ras, mm_per_unit, item);
    }
  }
  return collector.Finish();
}

// ---- writers ----

std::string MarkupsJson(const LandmarkSet& landmarks) {
  using ordered = nlohmann::ordered_json;
  ordered points = ordered::array();
  for (std::size_t i = 0; i < landmarks.items.size(); ++i) {
    const Landmark& l = landmarks.items[i];
    points.push_back(ordered{{"id", std::to_string(i + 1)},
                             {"label", l.label},
                             {"description", l.description},
                             {"associatedNodeID", ""},
                             {"position", {l.position.x(), l.position.y(), l.position.z()}},
                             {"orientation", {-1.0, -0.0, -0.0, -0.0, -1.0, -0.0, 0.0, 0.0, 1.0}},
                             {"selected", true},
                             {"locked", false},
                             {"visibility", true},
                             {"positionStatus", "defined"}});
  }
  ordered markup{{"type", "Fiducial"},
                 {"coordinateSystem", "LPS"},
                 {"coordinateUnits", "mm"},
                 {"locked", false},
                 {"fixedNumberOfControlPoints", false},
                 {"labelFormat", "%N-%d"},
                 {"lastUsedControlPointNumber", landmarks.items.size()},
                 {"controlPoints", std::move(points)}};
  const ordered root{{"@schema", kMarkupsSchema}, {"markups", ordered::array({std::move(markup)})}};
  return root.dump(4) + "\n";
}

// One field of a line-based format: newlines in a description become spaces.
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

}  // namespace

LandmarkSet ParseLandmarks(std::string_view bytes, const std::string& name,
                           const LandmarkReadOptions& options) {
  const LandmarkFormat format = FormatOf(name);
  bytes = text::StripBom(bytes);
  if (bytes.find_first_not_of(" \t\r\n\v\f") == std::string_view::npos) ThrowBadInput(name, "file is empty");
  const double mm_per_unit = MillimetresPer(options.input_units);
  switch (format) {
    case LandmarkFormat::kMarkupsJson: try { return ParseMarkupsJson(bytes, name, mm_per_unit);
      } catch (const nlohmann::json::exception& e) {
        ThrowBadInput(name, "unexpected JSON content: " + JsonErrorText(e));
      }
    case LandmarkFormat::kFcsv: return ParseFcsv(bytes, name, mm_per_unit);
    case LandmarkFormat::kCsv: return ParseCsv(bytes, name, mm_per_unit);
  }
  return {};
}

LandmarkSet ReadLandmarks(const std::filesystem::path& path, const LandmarkReadOptions& options) {
  const std::string name = path.string();
  FormatOf(name);  // an unknown type is a usage error before the file is opened
  MappedFile file(name);
  return ParseLandmarks(file.bytes(), name, options);
}

void WriteLandmarks(const std::filesystem::path& path, const LandmarkSet& landmarks) {
  const std::string name = path.string();
  const LandmarkFormat format = FormatOf(name);
  landmarks.Validate(name);
  for (const Landmark& l : landmarks.items) {
    if (!text::IsValidUtf8(l.label) || !text::IsValidUtf8(l.description)) {
      ThrowUsage(name + ": landmark label or description is not valid UTF-8 text");
    }
    if (format != LandmarkFormat::kMarkupsJson && l.label.find_first_of("\r\n") != std::string::npos) {
      ThrowUsage(name + ": landmark label '" + l.label +
                 "' holds a line break, which this format cannot store");
    }
  }
  switch (format) {
    case LandmarkFormat::kMarkupsJson: WriteFileAtomically(path, MarkupsJson(landmarks)); break;
    case LandmarkFormat::kFcsv: WriteFileAtomically(path, Fcsv(landmarks)); break;
    case LandmarkFormat::kCsv: WriteFileAtomically(path, Csv(landmarks)); break;
  }
}

}  // namespace pectus
