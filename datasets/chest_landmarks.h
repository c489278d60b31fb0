// pectus datasets: the eleven markers a clinician places on a chest scan, at fixed surface parameters.
#pragma once

#include <string>
#include <vector>

#include "datasets/chest_surface.h"
#include "shape/core/landmarks.h"

namespace pectus::datasets {

/// One landmark of the chest model: its label, what it marks, and where on the surface (u, v).
struct LandmarkDefinition {
  std::string label;        ///< e.g. "sternal_notch"
  std::string description;  ///< anatomical feature
  double u = 0.0;           ///< surface parameter across (-1 right, +1 left)
  double v = 0.0;           ///< surface parameter up (0 bottom, 1 top)
};

/// The 11 landmarks, in this order: sternal_notch, manubrium_centre, sternal_angle, mid_sternum, xiphoid,
/// costal_cartilage_1_left, costal_cartilage_1_right, costal_cartilage_4_left, costal_cartilage_4_right,
/// costal_margin_left, costal_margin_right. The dissertation (section 4.3.1) uses the sternal notch ("red"),
/// the xiphoid ("blue") and the first left costal cartilage ("yellow") to bound its grid.
const std::vector<LandmarkDefinition>& ChestLandmarkDefinitions();

/// The definition with this label; throws Error(kUsage) if there is none.
const LandmarkDefinition& FindLandmarkDefinition(const std::string& label);

/// The true landmarks of a surface (exactly on it), in the scan frame, mm.
LandmarkSet TrueLandmarks(const ChestSurface& surface);

}  // namespace pectus::datasets
