// pectus planner: measuring a ribcage the way the CT measurements were taken (dissertation §4.1.1,
// Figures 22-23): on the axial slice of deepest depression, the width, depth, sternal depression and
// torsion; the sternal length from the first and last slices showing the sternum; the Haller index.
#pragma once

#include <Eigen/Core>
#include <string>

#include "shape/core/geometry.h"

namespace pectus::planner {

/// A ribcage's bone surface, as the measurements see it.
struct RibcageSurface {
  Points3 nodes;  ///< #nodes by 3 positions, mm, LPS (x left, y posterior, z superior)
  Faces3 faces;   ///< #faces by 3 boundary triangles of the bones
  Eigen::VectorXi
      face_parts;  ///< #faces: 0 on the sternum, k != 0 on rib k (left) or -k (right) with its cartilage
  Points3 spine_anterior;  ///< polyline of the anterior surface of the vertebral bodies, z decreasing
};

/// Options of the measurements.
struct RibcageMeasurementOptions {
  /// Spacing of the candidate axial slices searched for the deepest depression, mm. Default 0.5.
  double slice_step_mm = 0.5;
  /// The slices searched: this range of the sternal height, as fractions from the notch. Defaults
  /// 0.3 (the sternal angle) to 0.9 (the xiphisternal joint): the sternal body.
  double search_from = 0.3, search_to = 0.95;
  /// Where the slice is taken when the chest is flat (no depression anywhere), fraction of the sternal
  /// height from the notch; among slices of (nearly) equal depression the one nearest this level wins.
  /// Default 0.75.
  double flat_level = 0.75;
  /// The slice is a soft maximum: the levels, weighted by exp((depression - deepest) / softness), are
  /// averaged, so "the slice of deepest depression" moves continuously with the ribcage instead of
  /// hopping between two nearly equally deep levels, mm. Default 0.1.
  double slice_softness_mm = 0.1;
  bool IsValid(std::string* why) const;
};

/// What the measurements found. Lengths in mm, angles in degrees.
struct RibcageMeasurements {
  double width_mm = 0;           ///< outer transverse extent of the bones on the slice
  double depth_mm = 0;           ///< antero-posterior extent of the bones on the slice
  double sternal_length_mm = 0;  ///< height (z extent) of the sternum: first to last axial slice showing it
  double depression_mm =
      0;                   ///< highest (most anterior) point of the ribcage to the sternum's anterior surface
  double torsion_deg = 0;  ///< sternal rotation on the slice; positive when its right edge lies deeper
  double inner_width_mm = 0;       ///< transverse extent between the inner surfaces of the widest ribs
  double sternum_to_spine_mm = 0;  ///< posterior surface of the sternum to the anterior surface of the spine
  double haller_index = 0;         ///< inner_width_mm / sternum_to_spine_mm
  double slice_z_mm = 0;           ///< height of the slice of deepest depression
  double notch_z_mm = 0;           ///< height of the top of the sternum
  /// One line with all values.
  std::string BriefReport() const;
};

/// Measures `surface`. Throws Error(kBadInput) if it has no sternum faces or no slice through the
/// sternum, or if the spine line does not reach the slice.
RibcageMeasurements MeasureRibcage(const RibcageSurface& surface,
                                   const RibcageMeasurementOptions& options = {});

/// Depression profile: (z, depression) on every searched slice, mm (for plots and tests).
std::vector<std::pair<double, double>> DepressionProfile(const RibcageSurface& surface,
                                                         const RibcageMeasurementOptions& options = {});

}  // namespace pectus::planner
