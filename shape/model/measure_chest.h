// pectus: pectus measures from a chest surface: the depth of the depression under a straight edge laid
// across the chest, and, when the surface goes round the torso, the external Haller index and external
// correction index (definitions and sources in docs/model.md).
#pragma once

#include <Eigen/Core>
#include <nlohmann/json.hpp>
#include <string>

#include "shape/core/geometry.h"
#include "shape/model/compute_chest_roi.h"

namespace pectus {

/// How the measures are taken.
struct ChestMeasuresOptions {
  int levels = 101;  ///< transverse sections between the notch and the xiphoid (>= 2)
  /// The sections start this fraction of the notch-to-xiphoid distance below the notch, in [0, 1): the
  /// suprasternal notch (a normal hollow about 8 mm deep) and the manubrium are not a depression.
  double first_level_fraction = 0.25;
  double bin_mm = 1.0;              ///< lateral resolution of each section's front profile (> 0, mm)
  double lateral_reach_mm = 150.0;  ///< the straight edge rests on the chest within this of the midline

  /// False, with the reason, for a value out of range.
  bool IsValid(std::string* why) const;
};

/// The measures. Depths are along the ROI normal (anterior), in mm; NaN where a measure needs more of the
/// torso than the surface has.
struct ChestMeasures {
  double depression_depth_mm =
      0.0;  ///< largest gap between the straight edge and the skin (0: no depression)
  double depression_level_mm = 0.0;    ///< sternal coordinate v of that section (0 at the notch)
  double depression_lateral_mm = 0.0;  ///< lateral coordinate u of the deepest point
  Eigen::Vector3d deepest_point = Eigen::Vector3d::Zero();  ///< on the skin, in the surface's frame
  bool closed_section = false;                 ///< the surface goes round the torso at that level
  double chest_width_mm = NAN;                 ///< transverse extent of the section
  double ap_depth_min_mm = NAN;                ///< deepest skin point to the back line
  double ap_depth_max_mm = NAN;                ///< most anterior skin point of the section to the back line
  double external_haller_index = NAN;          ///< width / ap_depth_min
  double external_correction_index_pct = NAN;  ///< (ap_depth_max - ap_depth_min) / ap_depth_max * 100
  std::string message;

  /// The measures as JSON (null for NaN).
  nlohmann::json ToJson() const;
};

/// Measures `surface` (a mesh, mm) in the frame of `roi`. For each transverse section from the upper
/// sternal body (first_level_fraction) to the xiphoid, a straight edge rests on the most anterior skin point
/// on each side of the midline; the depression depth is the largest gap between the edge and the skin between
/// them. At the section of the deepest gap, if the section is closed (no boundary edge of the mesh crosses
/// it), the width and the antero-posterior depths give the external indices. Throws Error(kBadInput) naming
/// `what` for a surface without faces or one that no section reaches on both sides of the midline.
ChestMeasures MeasureChest(const TriangleMesh& surface, const ChestRoi& roi,
                           const ChestMeasuresOptions& options = {}, const std::string& what = "surface");

}  // namespace pectus
