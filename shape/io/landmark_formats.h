// pectus: the landmark formats behind landmark_io.h, one source file per format (internal header):
// landmark_json_io.cc (.mrk.json), landmark_fcsv_io.cc (.fcsv), landmark_csv_io.cc (.csv, and the rows
// both CSV-like formats share). Each parser reads from memory; `name` is the file named in errors.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <map>
#include <string>
#include <string_view>
#include <vector>

#include "shape/core/landmarks.h"

namespace pectus::landmark_formats {

/// Gathers landmarks from any format: converts RAS to LPS and units to mm, and rejects empty, invalid
/// UTF-8 or duplicate labels and non-finite positions, naming the line (or control point) at fault.
class Collector {
 public:
  /// `item_word` names an item in errors: "line" (text formats) or "control point" (JSON).
  Collector(const std::string& name, const char* item_word) : name_(name), item_word_(item_word) {}

  /// Adds one landmark; `item` is the line number (text formats) or the control point number (JSON).
  void Add(const std::string& label, const std::string& description, Eigen::Vector3d position, bool ras,
           double mm_per_unit, std::int64_t item);

  /// Throws Error(kBadInput) naming the file and the item.
  [[noreturn]] void Fail(const std::string& message, std::int64_t item) const;

  /// The landmarks gathered; Error(kBadInput) if there are none.
  LandmarkSet Finish();

 private:
  const std::string& name_;
  std::string item_word_;
  std::map<std::string, std::int64_t> first_item_;
  LandmarkSet set_;
};

/// Column positions of a CSV-like table (-1: absent).
struct CsvColumns {
  int label = 0, x = 1, y = 2, z = 3, description = 4;
  /// The number of fields a row needs to hold label, x, y and z.
  int Needed() const;
};

/// Adds the landmark of one CSV-like row (fields in `columns`) to `collector`; `line` names it in errors.
void AddRow(const std::vector<std::string>& fields, const CsvColumns& columns, bool ras, double mm_per_unit,
            Collector* collector, std::int64_t line);

/// One CSV field as written: quoted when it holds a comma, a quote or blanks at either end.
std::string QuoteCsv(const std::string& field);
/// One field of a line-based format: newlines in a description become spaces.
std::string OneLine(std::string s);
/// Appends ",x,y,z" (shortest round-trip numbers) to `*out`.
void AppendXyz(const Eigen::Vector3d& p, std::string* out);

/// 3D Slicer markups (.mrk.json): every "Fiducial" markup's defined control points.
LandmarkSet ParseMarkupsJson(std::string_view bytes, const std::string& name, double default_mm_per_unit);
/// The Slicer 5 markups schema, coordinateSystem LPS, in mm.
std::string MarkupsJson(const LandmarkSet& landmarks);
/// nlohmann's error message without its bracketed id.
std::string JsonErrorText(const std::exception& e);

/// Legacy Slicer fiducial list (.fcsv): RAS unless the header says LPS; columns from "# columns =".
LandmarkSet ParseFcsv(std::string_view bytes, const std::string& name, double mm_per_unit);
/// The version 4.11 header, LPS.
std::string Fcsv(const LandmarkSet& landmarks);

/// CSV label,x,y,z[,description], optionally under a header naming the columns; taken as it stands.
LandmarkSet ParseCsv(std::string_view bytes, const std::string& name, double mm_per_unit);
/// label,x,y,z (and description when any landmark has one).
std::string Csv(const LandmarkSet& landmarks);

}  // namespace pectus::landmark_formats
