#include "planner_plugin/ribcage/sternum_skinning.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

#include "shape/core/error.h"

namespace pectus::planner {
namespace {

double Smoothstep(double t) {
  t = std::clamp(t, 0.0, 1.0);
  return t * t * (3 - 2 * t);
}

// 1 up to `inner`, 0 beyond `outer`, smootherstep (C2) in between.
double FallOff(double d, double inner, double outer) {
  const double t = std::clamp((d - inner) / (outer - inner), 0.0, 1.0);
  return 1.0 - t * t * t * (t * (6 * t - 15) + 10);
}

// Across the chest: 1 up to `inner`, 0 beyond `outer`, a quarter sine in between: steepest at the inner
// envelope and flat at the outer (continuous with one derivative there), so that beside the sternum the
// chest wall rises at once from the sternum's depth, as a saucer does.
double LateralFallOff(double d, double inner, double outer) {
  const double t = std::clamp((d - inner) / (outer - inner), 0.0, 1.0);
  return 1.0 - std::sin(0.5 * M_PI * t);
}

}  // namespace

bool SternumSkinningOptions::IsValid(std::string* why) const {
  if (!(inner_envelope_mm >= 0 && outer_envelope_mm > inner_envelope_mm && posterior_inner_mm >= 0 &&
        posterior_outer_mm > posterior_inner_mm)) {
    if (why) *why = "envelopes must satisfy 0 <= inner < outer";
    return false;
  }
  return true;
}

SternumSkinning::SternumSkinning(Points3 axis, std::vector<double> half_width, double ramp_from,
                                 double ramp_to, double scale, const SternumSkinningOptions& options)
    : axis_(std::move(axis)),
      half_width_(std::move(half_width)),
      ramp_from_(ramp_from),
      ramp_to_(ramp_to),
      scale_(scale),
      options_(options) {
  if (axis_.rows() < 2 || static_cast<Eigen::Index>(half_width_.size()) != axis_.rows() ||
      !(ramp_to > ramp_from)) {
    ThrowFailure("sternum skinning: need an axis of two or more points with one half-width each");
  }
  std::string why;
  if (!options.IsValid(&why)) ThrowUsage("sternum skinning options: " + why);
  // Arc-length fractions of the axis points.
  fraction_.assign(static_cast<std::size_t>(axis_.rows()), 0.0);
  for (Eigen::Index i = 1; i < axis_.rows(); ++i) {
    fraction_[i] = fraction_[i - 1] + (axis_.row(i) - axis_.row(i - 1)).norm();
  }
  for (double& f : fraction_) f /= fraction_.back();
  hinge_ = AtFraction(ramp_from_);
  reference_ = AtFraction(kReferenceFraction);
}

Eigen::Vector3d SternumSkinning::AtFraction(double fraction) const {
  const auto it = std::lower_bound(fraction_.begin(), fraction_.end(), fraction);
  const Eigen::Index i = std::clamp<Eigen::Index>(it - fraction_.begin(), 1, axis_.rows() - 1);
  const double t = std::clamp((fraction - fraction_[i - 1]) / (fraction_[i] - fraction_[i - 1]), 0.0, 1.0);
  return (axis_.row(i - 1) + t * (axis_.row(i) - axis_.row(i - 1))).transpose();
}

double SternumSkinning::HingeAngle(double depression_mm) const {
  // Rotating r = reference - hinge (in the y-z plane) by a about +x moves its y to r_y cos a - r_z sin a
  // = rho cos(a + beta); solve rho cos(a + beta) = r_y + depression on the branch through a = 0.
  const double r_y = reference_.y() - hinge_.y(), r_z = reference_.z() - hinge_.z();
  const double rho = std::hypot(r_y, r_z), beta = std::atan2(r_z, r_y);
  const double c = std::clamp((r_y + depression_mm) / rho, -1.0, 1.0);
  return beta < 0 ? -std::acos(c) - beta : std::acos(c) - beta;
}

SternumSkinning::AxisPoint SternumSkinning::Locate(const Eigen::Vector3d& p) const {
  // The axis descends monotonically in z: find the segment at p's height.
  const Eigen::Index n = axis_.rows();
  AxisPoint a;
  a.below = 0.0;
  Eigen::Index i = 0;
  double t = 0.0;
  if (p.z() >= axis_(0, 2)) {
    i = 0;
    t = 0.0;
  } else if (p.z() <= axis_(n - 1, 2)) {
    i = n - 2;
    t = 1.0;
    a.below = axis_(n - 1, 2) - p.z();
  } else {
    while (i + 2 < n && axis_(i + 1, 2) > p.z()) ++i;
    t = (axis_(i, 2) - p.z()) / (axis_(i, 2) - axis_(i + 1, 2));
  }
  const Eigen::Vector3d c0 = axis_.row(i).transpose(), c1 = axis_.row(i + 1).transpose();
  a.centre = c0 + t * (c1 - c0);
  a.direction = (c1 - c0).normalized();
  a.half_width = half_width_[i] + t * (half_width_[i + 1] - half_width_[i]);
  a.fraction = fraction_[i] + t * (fraction_[i + 1] - fraction_[i]);
  return a;
}

double SternumSkinning::Weight(const Eigen::Vector3d& p) const {
  const AxisPoint a = Locate(p);
  const double along = Smoothstep((a.fraction - ramp_from_) / (ramp_to_ - ramp_from_));
  const double lateral = std::max(0.0, std::abs(p.x() - a.centre.x()) - a.half_width);
  const double distance = std::hypot(lateral, a.below);
  const double across =
      LateralFallOff(distance, scale_ * options_.inner_envelope_mm, scale_ * options_.outer_envelope_mm);
  const double behind = p.y() - a.centre.y();
  const double depth =
      FallOff(behind, scale_ * options_.posterior_inner_mm, scale_ * options_.posterior_outer_mm);
  return along * across * depth;
}

Eigen::Vector3d SternumSkinning::Apply(const Eigen::Vector3d& p, double depression_mm,
                                       double torsion_rad) const {
  const double w = Weight(p);
  if (w == 0.0) return p;
  const AxisPoint a = Locate(p);
  const Eigen::Matrix3d hinge =
      Eigen::AngleAxisd(HingeAngle(depression_mm), Eigen::Vector3d::UnitX()).toRotationMatrix();
  const Eigen::Vector3d centre = hinge * (a.centre - hinge_) + hinge_;
  const Eigen::Vector3d moved =
      Eigen::AngleAxisd(torsion_rad, hinge * a.direction) * (hinge * (p - hinge_) + hinge_ - centre) + centre;
  return p + w * (moved - p);
}

}  // namespace pectus::planner
