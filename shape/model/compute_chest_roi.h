// pectus: the chest region of interest bounded by landmarks, and the frame of the resampling grid
// (dissertation §4.3.1, Fig. 35).
#pragma once

#include <Eigen/Core>
#include <nlohmann/json.hpp>
#include <string>

#include "shape/core/geometry.h"
#include "shape/core/landmarks.h"

namespace pectus {

/// Landmarks and margins that bound the region of interest.
struct ChestRoiOptions {
  std::string notch_label = "sternal_notch";                ///< bounds the ROI at the top
  std::string xiphoid_label = "xiphoid";                    ///< bounds the ROI at the bottom
  std::string cartilage_label = "costal_cartilage_1_left";  ///< with its mirror, bounds the sides
  double superior_margin_mm = 0.0;  ///< ROI extends this far above the notch (>= 0, mm)
  double inferior_margin_mm = 0.0;  ///< ... below the xiphoid
  double lateral_margin_mm = 0.0;   ///< ... beyond the cartilage and its mirror, on each side
  /// Optional anterior direction in the landmarks' frame (any length, not parallel to the sternal line).
  /// Zero (default): the lateral axis is the perpendicular from the sternal line to the cartilage, so
  /// the ROI plane passes through all three landmarks. Set: the lateral axis is perpendicular to both
  /// the sternal line and this direction (the plane is "level" left to right); the cartilage then only
  /// sets the width.
  Eigen::Vector3d anterior_hint = Eigen::Vector3d::Zero();

  /// False, with the reason in `why`, for an empty label or a negative or non-finite margin.
  bool IsValid(std::string* why) const;
};

/// A rectangle in a plane with an orthonormal frame. A point has ROI coordinates (u, v, w):
/// x = origin + u * lateral + v * sternal + w * normal, with u across the chest (positive toward the
/// cartilage, the subject's left), v along the sternal line (0 at the notch, positive toward the
/// xiphoid) and w the depth (positive anterior, out of the chest). All in mm.
struct ChestRoi {
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();    ///< the sternal notch, mm
  Eigen::Vector3d lateral = Eigen::Vector3d::UnitX();  ///< unit; toward the cartilage
  Eigen::Vector3d sternal = Eigen::Vector3d::UnitY();  ///< unit; notch to xiphoid
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();   ///< unit; sternal x lateral, anterior
  double u_min = 0.0, u_max = 0.0;                     ///< lateral extent of the rectangle, mm
  double v_min = 0.0, v_max = 0.0;                     ///< sternal extent of the rectangle, mm

  /// ROI coordinates (u, v, w) of #n by 3 points (mm).
  Points3 ToRoi(const Points3& points) const;
  /// Points (#n by 3, mm) from #n by 3 ROI coordinates (u, v, w).
  Points3 FromRoi(const Points3& uvw) const;
  /// One point from its ROI coordinates.
  Eigen::Vector3d FromRoi(double u, double v, double w) const {
    return origin + u * lateral + v * sternal + w * normal;
  }
  double width() const { return u_max - u_min; }   ///< lateral extent, mm
  double height() const { return v_max - v_min; }  ///< sternal extent, mm
  /// The ROI moved by T: the origin mapped, the axes rotated, the extents scaled by T.scale (so that a
  /// point's ROI coordinates in the new frame are T.scale times those in the old).
  ChestRoi Transformed(const Similarity3& T) const;
  /// {"origin", "lateral", "sternal", "normal", "u_range_mm", "v_range_mm"}.
  nlohmann::json ToJson() const;
};

/// The ROI of one subject from its landmarks: origin at the notch, sternal axis to the xiphoid,
/// lateral axis through the cartilage (see ChestRoiOptions::anterior_hint), normal = sternal x lateral
/// (anterior for a right-handed frame and an anatomically placed cartilage on the subject's left).
/// The rectangle spans v in [-superior margin, |xiphoid - notch| + inferior margin] and u in
/// [-(c + lateral margin), c + lateral margin], c = lateral coordinate of the cartilage (its mirror
/// about the sternal line is at -c).
/// Throws Error(kBadInput) naming `what` for a missing landmark, coincident notch and xiphoid (< 1 mm)
/// or a cartilage on the sternal line (< 1 mm off it); Error(kUsage) for invalid options.
ChestRoi ComputeChestRoi(const LandmarkSet& landmarks, const ChestRoiOptions& options = {},
                         const std::string& what = "landmarks");

}  // namespace pectus
