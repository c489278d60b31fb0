// Transforms as JSON: "T_target_source" as a 4 by 4 matrix (nested rows or 16 numbers, row-major).
#include "shape/io/transform_io.h"

#include <cmath>
#include <numbers>
#include <string>

#include "shape/core/atomic_file.h"
#include "shape/core/error.h"
#include "shape/io/mapped_file.h"

namespace pectus {
namespace {

constexpr double kScaleTolerance = 1e-6;  // relative

std::string JsonErrorText(const nlohmann::json::exception& e) {
  std::string what = e.what();
  const std::size_t close = what.find("] ");
  return close == std::string::npos ? what : what.substr(close + 2);
}

double Number(const nlohmann::json& value, const std::string& name, const std::string& where) {
  if (!value.is_number()) ThrowBadInput(name, where + " is " + value.dump() + ", not a number");
  return value.get<double>();
}

Eigen::Matrix4d MatrixFromJson(const nlohmann::json& m, const std::string& name) {
  const std::string shape = "\"T_target_source\" must be 4 rows of 4 numbers or 16 numbers (row-major)";
  if (!m.is_array()) ThrowBadInput(name, shape);
  Eigen::Matrix4d M;
  if (m.size() == 16) {
    for (int i = 0; i < 16; ++i) {
      M(i / 4, i % 4) = Number(m[static_cast<std::size_t>(i)], name, "entry " + std::to_string(i + 1));
    }
    return M;
  }
  if (m.size() != 4) ThrowBadInput(name, shape);
  for (int r = 0; r < 4; ++r) {
    const nlohmann::json& row = m[static_cast<std::size_t>(r)];
    if (!row.is_array() || row.size() != 4)
      ThrowBadInput(name, shape + "; row " + std::to_string(r + 1) + " is not");
    for (int c = 0; c < 4; ++c) {
      M(r, c) = Number(row[static_cast<std::size_t>(c)], name,
                       "row " + std::to_string(r + 1) + ", column " + std::to_string(c + 1));
    }
  }
  return M;
}

}  // namespace

Similarity3 ParseTransformJson(const std::string& text, const std::string& name) {
  nlohmann::json root;
  try {
    root = nlohmann::json::parse(text);
  } catch (const nlohmann::json::exception& e) {  // parse_error, or out_of_range for 1e999
    ThrowBadInput(name, "malformed JSON: " + JsonErrorText(e));
  }
  if (!root.is_object() || !root.contains("T_target_source")) {
    ThrowBadInput(name,
                  "no \"T_target_source\" in the file (expected a JSON object holding a 4 by 4 matrix)");
  }
  const Eigen::Matrix4d M = MatrixFromJson(root["T_target_source"], name);
  Similarity3 T = Similarity3::FromMatrix(M, name);
  if (root.contains("scale")) {
    // A stated scale must agree with the matrix (a scale stated but not applied is a common mistake).
    const double stated = Number(root["scale"], name, "\"scale\"");
    if (!(std::abs(stated - T.scale) <= kScaleTolerance * std::abs(T.scale))) {
      ThrowBadInput(name, "\"scale\" is " + std::to_string(stated) +
                              " but the matrix's 3 by 3 block has scale " + std::to_string(T.scale) +
                              " (cube root of its determinant)");
    }
    // Where the two differ only by the rounding of the cube root (a few ulps), the stated scale is the
    // exact one: a rigid transform written with "scale": 1 reads back with scale 1, whichever compiler
    // rounded its determinant. Otherwise the matrix wins.
    if (std::abs(stated - T.scale) <= 1e-12 * std::abs(stated)) {
      T.rotation = M.topLeftCorner<3, 3>() / stated;
      T.scale = stated;
    }
  }
  return T;
}

Similarity3 ReadTransformJson(const std::filesystem::path& path) {
  MappedFile file(path.string());
  if (file.bytes().empty()) ThrowBadInput(path.string(), "file is empty");
  return ParseTransformJson(std::string(file.bytes()), path.string());
}

nlohmann::json TransformToJson(const Similarity3& T_target_source) {
  const Eigen::Matrix4d M = T_target_source.Matrix();
  nlohmann::json rows = nlohmann::json::array();
  for (int r = 0; r < 4; ++r) rows.push_back({M(r, 0), M(r, 1), M(r, 2), M(r, 3)});
  const double angle_deg = Eigen::AngleAxisd(T_target_source.rotation).angle() * 180.0 / std::numbers::pi;
  const Eigen::Vector3d& t = T_target_source.translation;
  return nlohmann::json{{"T_target_source", std::move(rows)},
                        {"scale", T_target_source.scale},
                        {"rotation_deg", angle_deg},
                        {"translation_mm", {t.x(), t.y(), t.z()}}};
}

void WriteTransformJson(const std::filesystem::path& path, const Similarity3& T_target_source,
                        const nlohmann::json& extra) {
  if (!extra.is_object())
    ThrowUsage(path.string() + ": extra fields of a transform file must be a JSON object");
  // The transform's own fields win over any of the same name in `extra`.
  nlohmann::json out = extra;
  out.update(TransformToJson(T_target_source));
  WriteFileAtomically(path, out.dump(2) + "\n");
}

}  // namespace pectus
