// pectus datasets: CT-style measurements of a chest surface — width, depth and sternal depression on the
// axial slice of deepest depression, and the sternal length (dissertation section 3.3, figure 22).
#pragma once

#include <Eigen/Core>

#include "datasets/chest_surface.h"

namespace pectus::datasets {

/// Options for MeasureChest.
struct MeasureOptions {
  int samples_across = 721;  ///< points per axial slice
  int slices = 81;           ///< slices searched for the deepest depression, before refinement
  /// The search covers the sternal body: from this far above the xiphoid to this far below the notch, in
  /// sternal lengths (the xiphoid and manubrium regions carry the costal margins and the notch).
  double margin_below = 0.1, margin_above = 0.1;
  /// A concavity shallower than this (mm) counts as none: the slice is then the reference level (a normal
  /// chest wall has sub-millimetre dips between the costal margins that CT would not call a depression).
  double min_depression_mm = 0.5;
  /// The deepest point is sought within |x| <= this fraction of the half width (the front of the chest).
  double central_fraction = 0.7;
};

/// What MeasureChest finds. Lengths in mm in the subject frame (after growth, without the scan pose).
struct ChestMeasurement {
  double width_mm = 0.0;  ///< lateral extent of the slice (mid-axillary to mid-axillary)
  double depth_mm = 0.0;  ///< from the most anterior point of the slice to the back plane z = -growth_z D / 2
  double depression_mm = 0.0;      ///< along z, from the most anterior point of the slice back to the point
                                   ///< farthest behind its anterior convex hull (0 for a convex slice)
  double sternal_length_mm = 0.0;  ///< height from the sternal notch to the xiphoid landmark
  double slice_v = kVReference;    ///< surface parameter v of the slice (an axial plane: y depends on v only)
  double slice_y_mm = 0.0;         ///< height of the slice (y, subject frame)
  Eigen::Vector2d deepest_xz = Eigen::Vector2d::Zero();  ///< (x, z) of the deepest point of the concavity
};

/// Measures a surface as the dissertation measured CT: the axial slice of deepest depression is found
/// (argmax over slices of the depression, refined by golden section); on it, width is the lateral extent,
/// depth the distance from the most anterior point to the back plane (the model's back, z = -D / 2, since a
/// scan holds no back), and depression the distance (along z) from the most anterior point back to the
/// deepest point of the slice's concavity: the point farthest behind the slice's anterior convex hull. With
/// no concavity anywhere, the slice is the reference level. Measure the chest wall to compare with CT values.
ChestMeasurement MeasureChest(const ChestSurface& surface, const MeasureOptions& options = {});

}  // namespace pectus::datasets
