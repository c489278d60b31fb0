// pectus planner: the patient's sternal depression and torsion applied to the ribcage by skinning
// (dissertation §4.1.1, Figures 20-21): a bone in the sternum moves it, and every point follows with a
// weight that is 1 inside an inner envelope around the sternum and falls smoothly to 0 at an outer one.
// Across the chest the fall-off is steepest at the inner envelope (the sternum's edge by default), so
// that the chest wall beside the sternum rises at once from its depth, as in a saucer-shaped depression:
// with a flat start (a weight of 1 for 10 mm beyond the edge, then smootherstep, as before issue 14) the
// cartilages beside the sternum kept the chest's normal curvature at the sternum's depth and lay behind
// its back, and a flat bar met them first.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "shape/core/geometry.h"

namespace pectus::planner {

/// Envelopes of the sternal bone. Distances are measured from the sternum's lateral edge (and below
/// its lower tip), in mm at the generic ribcage's size; they scale with the ribcage width.
struct SternumSkinningOptions {
  /// Full weight within this distance of the sternum (the inner envelope), mm. Default 0.
  double inner_envelope_mm = 0.0;
  /// Zero weight beyond this distance (the outer envelope), mm. Default 85: the broad "saucer" type of
  /// the dissertation's patients takes the cartilages of both sides down with the sternum.
  double outer_envelope_mm = 85.0;
  /// Along the sternum the bone's influence rises from 0 at the joint of the second cartilage to 1 at
  /// the joint of the third (the first two cartilages are not deformed, per the surgeons); the lower
  /// sternum moves as one. Points deeper than these distances behind the sternum's axis are not moved
  /// (the back of the ribcage), mm: full weight up to `posterior_inner_mm`, none beyond
  /// `posterior_outer_mm`. Defaults 30 and 70.
  double posterior_inner_mm = 30.0;
  double posterior_outer_mm = 70.0;
  bool IsValid(std::string* why) const;
};

/// The skinning weights and the bone's motion for one ribcage.
class SternumSkinning {
 public:
  /// @param[in] axis        #stations by 3 points on the sternum's axis (section centres), notch first, mm
  /// @param[in] half_width  #stations half-widths of the sternum, mm
  /// @param[in] ramp_from   arc fraction where the weight starts to rise (second cartilage)
  /// @param[in] ramp_to     arc fraction where it reaches 1 (third cartilage)
  /// @param[in] scale       envelope distances are multiplied by this (ribcage width / generic width)
  SternumSkinning(Points3 axis, std::vector<double> half_width, double ramp_from, double ramp_to,
                  double scale, const SternumSkinningOptions& options);

  /// The weight of point p, in [0, 1]: the product of the fall-offs along the sternum and behind it
  /// (smootherstep: continuous with two derivatives) and across the chest (1 - sin(pi t / 2), t the
  /// distance beyond the inner envelope over the envelopes' gap: steepest at the inner envelope, flat at
  /// the outer).
  double Weight(const Eigen::Vector3d& p) const;
  /// p moved by the bone, blended by its weight w: p + w (B(p) - p). The bone B hinges the sternal body
  /// back about a transverse axis through the joint of the second cartilage (the sternal angle), by the
  /// angle that moves the reference point (the axis at `kReferenceFraction` of the arc, the lower sternal
  /// body) `depression_mm` posteriorly, then turns it by `torsion_rad` about its own (hinged) axis
  /// through the axis point at p's height (positive: the right edge goes posterior).
  /// @param[in] depression_mm  posterior displacement of the reference point, mm
  /// @param[in] torsion_rad    rotation of the bone about its axis, rad
  Eigen::Vector3d Apply(const Eigen::Vector3d& p, double depression_mm, double torsion_rad) const;

  /// The hinge angle (rad, about +x) that moves the reference point `depression_mm` posteriorly.
  double HingeAngle(double depression_mm) const;

  /// Arc fraction of the reference point (lower sternal body, just above the xiphisternal joint).
  static constexpr double kReferenceFraction = 0.85;

 private:
  struct AxisPoint {
    Eigen::Vector3d centre, direction;
    double half_width, fraction, below;
  };
  AxisPoint Locate(const Eigen::Vector3d& p) const;
  Eigen::Vector3d AtFraction(double fraction) const;

  Points3 axis_;
  std::vector<double> half_width_, fraction_;
  double ramp_from_, ramp_to_, scale_;
  Eigen::Vector3d hinge_, reference_;
  SternumSkinningOptions options_;
};

}  // namespace pectus::planner
