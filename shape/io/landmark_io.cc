// Landmark files: the format chosen by the name, the checks every format shares (landmark_formats.h).
#include "shape/io/landmark_io.h"

#include <nlohmann/json.hpp>
#include <string>

#include "shape/core/atomic_file.h"
#include "shape/core/error.h"
#include "shape/io/landmark_formats.h"
#include "shape/io/mapped_file.h"
#include "shape/io/text_scan.h"

namespace pectus {
namespace landmark_formats {

void Collector::Add(const std::string& label, const std::string& description, Eigen::Vector3d position,
                    bool ras, double mm_per_unit, std::int64_t item) {
  if (label.empty()) Fail("missing label", item);
  if (!text::IsValidUtf8(label)) Fail("label is not valid UTF-8 text", item);
  if (!text::IsValidUtf8(description)) Fail("description is not valid UTF-8 text", item);
  if (!position.allFinite()) Fail("landmark '" + label + "' has a non-finite coordinate (NaN or Inf)", item);
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

void Collector::Fail(const std::string& message, std::int64_t item) const {
  if (item_word_ == "line") ThrowBadInput(name_, message, item);
  ThrowBadInput(name_, item_word_ + " " + std::to_string(item) + ": " + message);
}

LandmarkSet Collector::Finish() {
  if (set_.items.empty()) ThrowBadInput(name_, "no landmarks in the file");
  return std::move(set_);
}

}  // namespace landmark_formats

namespace {

enum class LandmarkFormat { kMarkupsJson, kFcsv, kCsv };

LandmarkFormat FormatOf(const std::string& name) {
  if (text::EndsWithNoCase(name, ".json")) return LandmarkFormat::kMarkupsJson;
  if (text::EndsWithNoCase(name, ".fcsv")) return LandmarkFormat::kFcsv;
  if (text::EndsWithNoCase(name, ".csv")) return LandmarkFormat::kCsv;
  ThrowUsage(name + ": unknown landmark file type (pectus reads and writes .mrk.json, .fcsv and .csv)");
}

}  // namespace

LandmarkSet ParseLandmarks(std::string_view bytes, const std::string& name,
                           const LandmarkReadOptions& options) {
  namespace lf = landmark_formats;
  const LandmarkFormat format = FormatOf(name);
  bytes = text::StripBom(bytes);
  if (bytes.find_first_not_of(" \t\r\n\v\f") == std::string_view::npos) ThrowBadInput(name, "file is empty");
  const double mm_per_unit = MillimetresPer(options.input_units);
  switch (format) {
    case LandmarkFormat::kMarkupsJson: try { return lf::ParseMarkupsJson(bytes, name, mm_per_unit);
      } catch (const nlohmann::json::exception& e) {
        ThrowBadInput(name, "unexpected JSON content: " + lf::JsonErrorText(e));
      }
    case LandmarkFormat::kFcsv: return lf::ParseFcsv(bytes, name, mm_per_unit);
    case LandmarkFormat::kCsv: return lf::ParseCsv(bytes, name, mm_per_unit);
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
  namespace lf = landmark_formats;
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
    case LandmarkFormat::kMarkupsJson: WriteFileAtomically(path, lf::MarkupsJson(landmarks)); break;
    case LandmarkFormat::kFcsv: WriteFileAtomically(path, lf::Fcsv(landmarks)); break;
    case LandmarkFormat::kCsv: WriteFileAtomically(path, lf::Csv(landmarks)); break;
  }
}

}  // namespace pectus
