#include "datasets/chest_landmarks.h"

#include <cmath>
#include <numbers>

#include "shape/core/error.h"

namespace pectus::datasets {
namespace {

// (u, v) of a point at lateral coordinate xi = sin(theta) = x / (W / 2) and height s (sternal lengths above
// the reference level).
LandmarkDefinition At(const char* label, const char* description, double xi, double s) {
  return {label, description, std::asin(xi) / (std::numbers::pi / 2.0),
          formula::kVReference + s * formula::kSpan};
}

// Height of the costal margin at lateral coordinate xi (as in chest_formula.h).
double CostalMarginS(double xi) { return (formula::kSXiphoid + 0.05) - 0.85 * std::sqrt(xi * xi + 0.0025); }

}  // namespace

const std::vector<LandmarkDefinition>& ChestLandmarkDefinitions() {
  static const std::vector<LandmarkDefinition> definitions = {
      At("sternal_notch", "suprasternal (jugular) notch, top of the manubrium", 0.0, formula::kSNotch),
      At("manubrium_centre", "centre of the manubrium", 0.0, 0.55),
      At("sternal_angle", "sternal angle (manubriosternal joint)", 0.0, 0.41),
      At("mid_sternum", "middle of the sternal body", 0.0, 0.055),
      At("xiphoid", "xiphoid process (xiphisternal joint)", 0.0, formula::kSXiphoid),
      At("costal_cartilage_1_left",
         "first left costal cartilage at its rib (costochondral junction), below the clavicle", 0.40, 0.60),
      At("costal_cartilage_1_right",
         "first right costal cartilage at its rib (costochondral junction), below the clavicle", -0.40, 0.60),
      At("costal_cartilage_4_left", "fourth left costal cartilage at the sternum", 0.19, 0.12),
      At("costal_cartilage_4_right", "fourth right costal cartilage at the sternum", -0.19, 0.12),
      At("costal_margin_left", "left costal margin, mid-clavicular line", 0.42, CostalMarginS(0.42)),
      At("costal_margin_right", "right costal margin, mid-clavicular line", -0.42, CostalMarginS(-0.42)),
  };
  return definitions;
}

const LandmarkDefinition& FindLandmarkDefinition(const std::string& label) {
  for (const LandmarkDefinition& d : ChestLandmarkDefinitions()) {
    if (d.label == label) return d;
  }
  ThrowUsage("the chest model has no landmark '" + label + "'");
}

LandmarkSet TrueLandmarks(const ChestSurface& surface) {
  LandmarkSet set;
  for (const LandmarkDefinition& d : ChestLandmarkDefinitions()) {
    set.items.push_back({d.label, surface.Position(d.u, d.v), d.description});
  }
  return set;
}

}  // namespace pectus::datasets
