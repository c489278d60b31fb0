#include "shape/io/patient_table_io.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <sstream>

#include "shape/core/error.h"
#include "shape/io/csv_reader.h"
#include "shape/io/text_scan.h"

namespace pectus {
namespace {

/// A numeric column: where it goes in the row, whether the header must name it, and its range.
struct Column {
  const char* name;
  double PatientTableRow::*field;
  bool required;
  double lo, hi;
  bool image_length;  ///< measured in the image plane: the range is on the value / magnification
};

constexpr Column kColumns[] = {
    {"width_mm", &PatientTableRow::width_mm, true, 100, 500, true},
    {"sternal_length_mm", &PatientTableRow::sternal_length_mm, true, 40, 400, false},
    {"depth_mm", &PatientTableRow::depth_mm, true, 60, 400, true},
    {"depression_mm", &PatientTableRow::depression_mm, true, 0, 60, true},
    {"haller_index", &PatientTableRow::haller_index, false, 0, 100, false},
    {"magnification", &PatientTableRow::magnification, false, 0.2, 5, false},
    {"torsion_deg", &PatientTableRow::torsion_deg, false, -45, 45, false},
};

std::string Text(double value) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%g", value);
  return buffer;
}

class RowParser {
 public:
  RowParser(const std::string& name, std::int64_t line, const std::vector<std::string>& cells,
            const std::map<std::string, std::size_t, std::less<>>& column)
      : name_(name), line_(line), cells_(cells), column_(column) {}

  [[noreturn]] void Fail(std::string_view column, const std::string& message) const {
    ThrowBadInput(name_, "column '" + std::string(column) + "': " + message, line_);
  }

  /// The number in `column`; `fallback` if the header has no such column.
  double Number(std::string_view column, double fallback) const {
    const auto it = column_.find(column);
    if (it == column_.end()) return fallback;
    if (it->second >= cells_.size() || cells_[it->second].empty()) Fail(column, "no value");
    double value = 0.0;
    const std::string& cell = cells_[it->second];
    if (!text::ParseDouble(cell, &value) || !std::isfinite(value)) {
      Fail(column, text::Quoted(cell) + " is not a number");
    }
    return value;
  }

 private:
  const std::string& name_;
  std::int64_t line_;
  const std::vector<std::string>& cells_;
  const std::map<std::string, std::size_t, std::less<>>& column_;
};

PatientTableRow ParseRow(const RowParser& cells, std::int64_t line) {
  PatientTableRow row;
  row.line = line;
  const double patient = cells.Number("patient", 0.0);
  if (patient != std::floor(patient) || patient < 1 || patient > 1e6) {
    cells.Fail("patient", Text(patient) + " is not a patient number (a whole number from 1)");
  }
  row.patient = static_cast<int>(patient);
  for (const Column& c : kColumns) row.*c.field = cells.Number(c.name, row.*c.field);
  // Ranges after the magnification is known: image lengths are checked at their true size.
  for (const Column& c : kColumns) {
    const double value = row.*c.field;
    const double true_value = c.image_length ? value / row.magnification : value;
    if (!(true_value >= c.lo && true_value <= c.hi)) {
      std::string range = "must be " + Text(c.lo) + " to " + Text(c.hi);
      if (c.image_length && row.magnification != 1.0) {
        range +=
            " divided by the magnification " + Text(row.magnification) + " (it is " + Text(true_value) + ")";
      }
      cells.Fail(c.name, Text(value) + " is out of range: " + range);
    }
  }
  if (row.depth_mm > row.width_mm) {
    cells.Fail("depth_mm", Text(row.depth_mm) + " exceeds the width " + Text(row.width_mm));
  }
  if (row.depression_mm > 0.5 * row.depth_mm) {
    cells.Fail("depression_mm", Text(row.depression_mm) + " exceeds half the depth " + Text(row.depth_mm));
  }
  return row;
}

/// "1-3, 7, 9-62": the patient numbers, runs joined.
std::string ListPatients(const std::vector<PatientTableRow>& rows) {
  std::vector<int> numbers;
  for (const PatientTableRow& r : rows) numbers.push_back(r.patient);
  std::sort(numbers.begin(), numbers.end());
  std::string out;
  for (std::size_t i = 0; i < numbers.size();) {
    std::size_t j = i;
    while (j + 1 < numbers.size() && numbers[j + 1] == numbers[j] + 1) ++j;
    out += (out.empty() ? "" : ", ") + std::to_string(numbers[i]);
    if (j > i) out += "-" + std::to_string(numbers[j]);
    i = j + 1;
  }
  return out;
}

}  // namespace

std::vector<PatientTableRow> ParsePatientTable(std::string_view text, const std::string& name) {
  CsvReader reader(text, name);
  CsvRecord record;
  std::map<std::string, std::size_t, std::less<>> column;
  std::vector<PatientTableRow> rows;
  std::map<int, std::int64_t> line_of;
  while (reader.Next(&record)) {
    const std::vector<std::string>& cells = record.fields;
    if (column.empty()) {
      for (std::size_t c = 0; c < cells.size(); ++c) {
        if (!column.emplace(std::string(cells[c]), c).second) {
          ThrowBadInput(name, "the header names column '" + std::string(cells[c]) + "' twice", record.line);
        }
      }
      for (const char* required :
           {"patient", kColumns[0].name, kColumns[1].name, kColumns[2].name, kColumns[3].name}) {
        if (!column.count(required)) {
          ThrowBadInput(name, std::string("the header has no column '") + required + "'", record.line);
        }
      }
      continue;
    }
    rows.push_back(ParseRow(RowParser(name, record.line, cells, column), record.line));
    const auto [it, fresh] = line_of.emplace(rows.back().patient, record.line);
    if (!fresh) {
      ThrowBadInput(name,
                    "column 'patient': patient " + std::to_string(rows.back().patient) +
                        " is already on line " + std::to_string(it->second),
                    record.line);
    }
  }
  if (column.empty()) ThrowBadInput(name, "empty patient table (no header)");
  if (rows.empty()) ThrowBadInput(name, "the patient table has a header but no patients");
  return rows;
}

std::vector<PatientTableRow> ReadPatientTable(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::error_code ec;
  if (!in || std::filesystem::is_directory(path, ec))
    ThrowBadInput(path.string(), "cannot read the patient table");
  std::stringstream buffer;
  buffer << in.rdbuf();
  return ParsePatientTable(buffer.str(), path.string());
}

const PatientTableRow& FindPatient(const std::vector<PatientTableRow>& rows, int number,
                                   const std::string& table) {
  for (const PatientTableRow& r : rows) {
    if (r.patient == number) return r;
  }
  ThrowUsage("patient " + std::to_string(number) + " is not in " + table + " (patients " +
             ListPatients(rows) + ")");
}

const PatientTableRow& FindPatient(const std::vector<PatientTableRow>& rows, std::string_view id,
                                   const std::string& table) {
  std::int64_t number = 0;
  if (!text::ParseInt(text::Trim(id), &number) || number < 1 || number > 1000000) {
    ThrowUsage("patient " + text::Quoted(id) + " is not a patient number (" + table + " has patients " +
               ListPatients(rows) + ")");
  }
  return FindPatient(rows, static_cast<int>(number), table);
}

}  // namespace pectus
