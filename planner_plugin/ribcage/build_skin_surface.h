// pectus planner: the skin over the anterior chest wall (the bone surface plus a soft-tissue layer), so
// that a predicted chest can be compared with the average chest of the shape model. The skin follows the
// ribcage's finite element displacements through fixed interpolation weights.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "planner_plugin/ribcage/patient_ribcage.h"
#include "shape/core/geometry.h"
#include "shape/core/landmarks.h"

namespace pectus::planner {

/// Extent, resolution and thickness of the skin.
struct SkinSurfaceOptions {
  /// Soft-tissue thickness over the bones, mm (skin, fat and muscle of the anterior chest wall).
  /// Default 15.
  double soft_tissue_mm = 15.0;
  /// Angular extent on each side of the anterior midline, degrees (90 reaches the flanks). Default 75.
  double half_angle_deg = 75.0;
  /// From this far above the sternal notch, mm. Default 10.
  double above_notch_mm = 10.0;
  /// To this far below the xiphoid tip, mm. Default 20.
  double below_xiphoid_mm = 20.0;
  /// Grid: rows (top to bottom) and columns (right to left across the front). Defaults 64 and 96.
  int rows = 64, columns = 96;
  /// The skin bridges the gaps between ribs: bone nodes within this Gaussian reach (mm, along the
  /// chest and along the body) of a skin point's ray define it, the outermost weighted most. Default 6.
  double reach_mm = 6.0;
  bool IsValid(std::string* why) const;
};

/// A material point of the skin: a fixed combination of skin vertices, so it moves with the skin.
struct SkinPoint {
  std::string label;
  std::string description;
  std::vector<std::pair<Eigen::Index, double>> weights;  ///< (skin vertex, weight), weights summing to 1
};

/// The skin of one patient: a grid of vertices over the chest wall, each tied to bone nodes.
struct SkinSurface {
  TriangleMesh mesh;  ///< (rows x columns) vertices, row-major from the top row, right to left; outward faces
  int rows = 0, columns = 0;
  Points3 outward;  ///< #vertices by 3 unit directions of the soft-tissue offset (horizontal rays)
  /// Per vertex: (mesh node, weight) pairs, weights summing to 1. The vertex lies on its horizontal ray
  /// from the chest's axis at the weighted depth of these bone nodes plus soft_tissue_mm.
  std::vector<std::vector<std::pair<std::int32_t, double>>> ties;
  double soft_tissue_mm = 0;
  /// The bone landmarks of the ribcage projected forward onto the skin (same labels: sternal_notch,
  /// manubrium_centre, sternal_angle, xiphoid, xiphoid_tip): where the skin's midline reaches each
  /// landmark's height, for registering the predicted chest to the average chest. Material points of
  /// the skin, so a deformed skin carries them along (Landmarks()).
  std::vector<SkinPoint> landmark_points;

  /// The skin moved with the ribcage: vertex j + sum_i w_ij u_i, for #mesh nodes by 3 displacements (mm).
  Points3 Deformed(const Points3& displacement) const;
  /// The skin landmarks on skin vertices `positions` (undeformed or Deformed()).
  LandmarkSet Landmarks(const Points3& positions) const;
};

/// Builds the skin over `ribcage` (its undeformed, patient-specific shape). Throws Error(kUsage) for
/// invalid options.
SkinSurface BuildSkinSurface(const PatientRibcage& ribcage, const SkinSurfaceOptions& options = {});

}  // namespace pectus::planner
