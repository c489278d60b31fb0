#include "datasets/chest_parameters.h"

#include <cmath>
#include <cstdio>

#include "datasets/internal/validation.h"
#include "shape/core/enum_names.h"
#include "shape/core/error.h"

namespace pectus::datasets {
namespace {

constexpr EnumNames<PectusType, 2> kTypeNames{{{PectusType::kSaucer, "saucer"}, {PectusType::kCup, "cup"}}};

using internal::Fail;
using internal::InRange;

// The named linear fields, in LinearPart order.
struct NamedField {
  const char* name;
  double ChestParameters::*field;
};
constexpr NamedField kNamedFields[] = {
    {"width_mm", &ChestParameters::width_mm},
    {"depth_mm", &ChestParameters::depth_mm},
    {"sternal_length_mm", &ChestParameters::sternal_length_mm},
    {"costal_recession_mm", &ChestParameters::costal_recession_mm},
    {"costal_ridge_mm", &ChestParameters::costal_ridge_mm},
    {"soft_tissue_mm", &ChestParameters::soft_tissue_mm},
    {"pectoral_mm", &ChestParameters::pectoral_mm},
    {"breast_mm", &ChestParameters::breast_mm},
    {"sternal_groove_mm", &ChestParameters::sternal_groove_mm},
    {"concavity_mm", &ChestParameters::concavity_mm},
    {"notch_mm", &ChestParameters::notch_mm},
    {"clavicle_mm", &ChestParameters::clavicle_mm},
};
constexpr int kNamedCount = static_cast<int>(std::size(kNamedFields));
static_assert(kNamedCount + kDetailCoefficients == kLinearParameterCount);

double Number(const nlohmann::json& j, const char* key, const std::string& what) {
  if (!j.contains(key) || !j[key].is_number())
    ThrowBadInput(what, std::string("missing number \"") + key + "\"");
  return j[key].get<double>();
}

nlohmann::json MatrixJson(const Eigen::Matrix4d& M) {
  nlohmann::json rows = nlohmann::json::array();
  for (int r = 0; r < 4; ++r) rows.push_back({M(r, 0), M(r, 1), M(r, 2), M(r, 3)});
  return rows;
}

}  // namespace

PectusType ParsePectusType(const std::string& text) {
  return ParseEnum(kTypeNames, text, [&] {
    return "unknown pectus type '" + text + "' (expected " + ListEnumNames(kTypeNames, "", ", ", " or ") +
           ")";
  });
}

std::string ToString(PectusType type) { return EnumToString(kTypeNames, type, "saucer"); }

bool PectusParameters::IsValid(std::string* why) const {
  if (!InRange(depth_mm, 0.0, 60.0)) return Fail(why, "pectus depth must be within [0, 60] mm");
  if (!InRange(centre_x_mm, -80.0, 80.0)) return Fail(why, "pectus centre_x must be within [-80, 80] mm");
  if (!InRange(centre_y_mm, -60.0, 80.0)) return Fail(why, "pectus centre_y must be within [-60, 80] mm");
  if (!InRange(width_mm, 0.0, 150.0) || (width_mm > 0.0 && width_mm < 5.0)) {
    return Fail(why, "pectus width must be 0 (default) or within [5, 150] mm");
  }
  if (!InRange(height_mm, 0.0, 150.0) || (height_mm > 0.0 && height_mm < 5.0)) {
    return Fail(why, "pectus height must be 0 (default) or within [5, 150] mm");
  }
  if (!InRange(asymmetry, -0.6, 0.6)) return Fail(why, "pectus asymmetry must be within [-0.6, 0.6]");
  if (!InRange(torsion_deg, -45.0, 45.0))
    return Fail(why, "sternal torsion must be within [-45, 45] degrees");
  if (!InRange(axis_deg, -60.0, 60.0)) return Fail(why, "pectus axis must be within [-60, 60] degrees");
  return true;
}

bool ChestParameters::IsValid(std::string* why) const {
  if (!InRange(width_mm, 120.0, 500.0)) return Fail(why, "chest width must be within [120, 500] mm");
  if (!InRange(depth_mm, 60.0, 400.0)) return Fail(why, "chest depth must be within [60, 400] mm");
  if (!InRange(sternal_length_mm, 60.0, 300.0))
    return Fail(why, "sternal length must be within [60, 300] mm");
  for (const NamedField& f : kNamedFields) {
    if (!InRange(this->*f.field, -100.0, 500.0))
      return Fail(why, std::string(f.name) + " is not a sane number");
  }
  if (detail_mm.size() != 0 && detail_mm.size() != kDetailCoefficients) {
    return Fail(why, "detail must be empty or hold " + std::to_string(kDetailCoefficients) + " coefficients");
  }
  if (detail_mm.size() && !detail_mm.allFinite()) return Fail(why, "detail coefficients must be finite");
  if (!(growth.array() > 0.2).all() || !(growth.array() < 5.0).all()) {
    return Fail(why, "growth factors must be within (0.2, 5)");
  }
  if (!T_scan_subject.matrix().allFinite()) return Fail(why, "subject pose must be finite");
  return pectus.IsValid(why);
}

Eigen::VectorXd LinearPart(const ChestParameters& p) {
  Eigen::VectorXd x = Eigen::VectorXd::Zero(kLinearParameterCount);
  for (int i = 0; i < kNamedCount; ++i) x(i) = p.*kNamedFields[i].field;
  if (p.detail_mm.size() == kDetailCoefficients) x.tail(kDetailCoefficients) = p.detail_mm;
  return x;
}

void SetLinearPart(const Eigen::VectorXd& x, ChestParameters* p) {
  if (x.size() != kLinearParameterCount) ThrowFailure("SetLinearPart: wrong vector size");
  for (int i = 0; i < kNamedCount; ++i) p->*kNamedFields[i].field = x(i);
  p->detail_mm = x.tail(kDetailCoefficients);
}

std::string LinearParameterName(int index) {
  if (index < kNamedCount) return kNamedFields[index].name;
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "detail_%03d", index - kNamedCount);
  return buffer;
}

ChestParameters Grow(const ChestParameters& p, const GrowthOptions& options) {
  ChestParameters q = p;
  q.growth.x() *= std::pow(1.0 + options.width_per_year, options.years);
  q.growth.y() *= std::pow(1.0 + options.height_per_year, options.years);
  q.growth.z() *= std::pow(1.0 + options.depth_per_year, options.years);
  q.pectus.depth_mm = std::min(60.0, p.pectus.depth_mm * options.pectus_depth_factor);
  return q;
}

nlohmann::json ToJson(const ChestParameters& p) {
  nlohmann::json j;
  for (const NamedField& f : kNamedFields) j[f.name] = p.*f.field;
  j["detail_mm"] = std::vector<double>(p.detail_mm.data(), p.detail_mm.data() + p.detail_mm.size());
  j["detail_grid"] = {kDetailU, kDetailV};
  const PectusParameters& e = p.pectus;
  j["pectus"] = {
      {"depth_mm", e.depth_mm},       {"type", ToString(e.type)},     {"centre_x_mm", e.centre_x_mm},
      {"centre_y_mm", e.centre_y_mm}, {"width_mm", e.width_mm},       {"height_mm", e.height_mm},
      {"asymmetry", e.asymmetry},     {"torsion_deg", e.torsion_deg}, {"axis_deg", e.axis_deg}};
  j["growth"] = {p.growth.x(), p.growth.y(), p.growth.z()};
  j["T_scan_subject"] = MatrixJson(p.T_scan_subject.matrix());
  return j;
}

ChestParameters ChestParametersFromJson(const nlohmann::json& j, const std::string& what) {
  if (!j.is_object()) ThrowBadInput(what, "chest parameters are not a JSON object");
  ChestParameters p;
  for (const NamedField& f : kNamedFields) p.*f.field = Number(j, f.name, what);
  if (j.contains("detail_mm")) {
    const auto d = j["detail_mm"].get<std::vector<double>>();
    p.detail_mm = Eigen::Map<const Eigen::VectorXd>(d.data(), static_cast<Eigen::Index>(d.size()));
  }
  if (j.contains("pectus")) {
    const nlohmann::json& e = j["pectus"];
    p.pectus.depth_mm = Number(e, "depth_mm", what);
    p.pectus.type = ParsePectusType(e.value("type", std::string("saucer")));
    p.pectus.centre_x_mm = Number(e, "centre_x_mm", what);
    p.pectus.centre_y_mm = Number(e, "centre_y_mm", what);
    p.pectus.width_mm = Number(e, "width_mm", what);
    p.pectus.height_mm = Number(e, "height_mm", what);
    p.pectus.asymmetry = Number(e, "asymmetry", what);
    p.pectus.torsion_deg = Number(e, "torsion_deg", what);
    p.pectus.axis_deg = Number(e, "axis_deg", what);
  }
  if (j.contains("growth")) {
    const auto g = j["growth"].get<std::vector<double>>();
    if (g.size() != 3) ThrowBadInput(what, "\"growth\" must hold 3 numbers");
    p.growth = Eigen::Vector3d(g[0], g[1], g[2]);
  }
  if (j.contains("T_scan_subject")) {
    Eigen::Matrix4d M;
    const nlohmann::json& rows = j["T_scan_subject"];
    if (!rows.is_array() || rows.size() != 4)
      ThrowBadInput(what, "\"T_scan_subject\" must be a 4 by 4 array");
    for (int r = 0; r < 4; ++r) {
      for (int c = 0; c < 4; ++c) M(r, c) = rows[r].at(c).get<double>();
    }
    p.T_scan_subject = Similarity3::FromMatrix(M, what + ": T_scan_subject").RigidPart();
  }
  std::string why;
  if (!p.IsValid(&why)) ThrowBadInput(what, why);
  return p;
}

}  // namespace pectus::datasets
