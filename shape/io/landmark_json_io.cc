// Landmark files: 3D Slicer markups (.mrk.json).
#include <nlohmann/json.hpp>
#include <string>

#include "shape/core/error.h"
#include "shape/io/landmark_formats.h"

namespace pectus::landmark_formats {
namespace {

constexpr const char* kMarkupsSchema =
    "https://raw.githubusercontent.com/slicer/slicer/master/Modules/Loadable/Markups/Resources/Schema/"
    "markups-schema-v1.0.3.json#";

}  // namespace

std::string JsonErrorText(const std::exception& e) {
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

}  // namespace pectus::landmark_formats
