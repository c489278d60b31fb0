#include "planner_plugin/ribcage/patient_table.h"

#include <charconv>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include "shape/core/error.h"

namespace pectus::planner {
namespace {

std::vector<std::string> SplitCsv(const std::string& line) {
  std::vector<std::string> fields;
  std::string field;
  std::istringstream in(line);
  while (std::getline(in, field, ',')) {
    const auto b = field.find_first_not_of(" \t\r\"");
    const auto e = field.find_last_not_of(" \t\r\"");
    fields.push_back(b == std::string::npos ? std::string() : field.substr(b, e - b + 1));
  }
  if (!line.empty() && line.back() == ',') fields.emplace_back();
  return fields;
}

double ParseNumber(const std::string& text, const std::string& column, const std::string& name,
                   std::int64_t line) {
  double value = 0;
  const char* end = text.data() + text.size();
  const auto [ptr, ec] = std::from_chars(text.data(), end, value);
  if (ec != std::errc() || ptr != end || text.empty()) {
    ThrowBadInput(name, "column '" + column + "': '" + text + "' is not a number", line);
  }
  return value;
}

}  // namespace

std::vector<PatientRow> ParsePatientTable(const std::string& text, const std::string& name) {
  std::istringstream in(text);
  std::string line;
  std::int64_t line_number = 0;
  std::map<std::string, std::size_t> column;
  while (std::getline(in, line)) {
    ++line_number;
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    const auto header = SplitCsv(line);
    for (std::size_t i = 0; i < header.size(); ++i) column[header[i]] = i;
    break;
  }
  for (const char* required : {"patient", "width_mm", "sternal_length_mm", "depth_mm", "depression_mm"}) {
    if (column.count(required) == 0)
      ThrowBadInput(name, std::string("missing column '") + required + "'", line_number);
  }
  std::vector<PatientRow> rows;
  std::set<std::string> seen;
  while (std::getline(in, line)) {
    ++line_number;
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    const auto fields = SplitCsv(line);
    auto get = [&](const std::string& c) -> std::string {
      const std::size_t i = column.at(c);
      if (i >= fields.size()) ThrowBadInput(name, "missing value for column '" + c + "'", line_number);
      return fields[i];
    };
    auto number = [&](const std::string& c) { return ParseNumber(get(c), c, name, line_number); };
    PatientRow row;
    PatientMeasurements& m = row.measurements;
    m.patient = get("patient");
    if (m.patient.empty()) ThrowBadInput(name, "empty patient identifier", line_number);
    if (!seen.insert(m.patient).second)
      ThrowBadInput(name, "patient '" + m.patient + "' appears twice", line_number);
    m.width_mm = number("width_mm");
    m.sternal_length_mm = number("sternal_length_mm");
    m.depth_mm = number("depth_mm");
    m.depression_mm = number("depression_mm");
    if (column.count("magnification")) m.magnification = number("magnification");
    if (column.count("torsion_deg")) m.torsion_deg = number("torsion_deg");
    if (column.count("haller_index")) row.haller_index = number("haller_index");
    std::string why;
    if (!m.IsValid(&why)) ThrowBadInput(name, why, line_number);
    rows.push_back(std::move(row));
  }
  if (rows.empty()) ThrowBadInput(name, "no patient rows");
  return rows;
}

std::vector<PatientRow> ReadPatientTable(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) ThrowBadInput(path.string(), "cannot open the patient table");
  std::stringstream buffer;
  buffer << in.rdbuf();
  return ParsePatientTable(buffer.str(), path.string());
}

const PatientRow& FindPatient(const std::vector<PatientRow>& rows, const std::string& patient) {
  for (const PatientRow& row : rows) {
    if (row.measurements.patient == patient) return row;
  }
  std::string list;
  for (const PatientRow& row : rows) list += (list.empty() ? "" : ", ") + row.measurements.patient;
  ThrowUsage("patient '" + patient + "' is not in the table (patients: " + list + ")");
}

}  // namespace pectus::planner
