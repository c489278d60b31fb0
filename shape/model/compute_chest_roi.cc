#include "shape/model/compute_chest_roi.h"

#include <cmath>

#include "shape/core/error.h"

namespace pectus {

bool ChestRoiOptions::IsValid(std::string* why) const {
  auto fail = [&](const std::string& m) {
    if (why != nullptr) *why = m;
    return false;
  };
  if (notch_label.empty() || xiphoid_label.empty() || cartilage_label.empty()) {
    return fail("ROI landmark labels must not be empty");
  }
  for (double m : {superior_margin_mm, inferior_margin_mm, lateral_margin_mm}) {
    if (!std::isfinite(m) || m < 0.0) return fail("ROI margins must be finite and >= 0 mm");
  }
  if (!anterior_hint.allFinite()) return fail("the anterior hint must be finite");
  return true;
}

Points3 ChestRoi::ToRoi(const Points3& points) const {
  Eigen::Matrix3d R;  // rows: lateral, sternal, normal
  R.row(0) = lateral.transpose();
  R.row(1) = sternal.transpose();
  R.row(2) = normal.transpose();
  Points3 uvw = (points.rowwise() - origin.transpose()) * R.transpose();
  return uvw;
}

Points3 ChestRoi::FromRoi(const Points3& uvw) const {
  Eigen::Matrix3d R;
  R.row(0) = lateral.transpose();
  R.row(1) = sternal.transpose();
  R.row(2) = normal.transpose();
  Points3 x = (uvw * R).rowwise() + origin.transpose();
  return x;
}

ChestRoi ChestRoi::Transformed(const Similarity3& T) const {
  ChestRoi out = *this;
  out.origin = T * origin;
  out.lateral = T.rotation * lateral;
  out.sternal = T.rotation * sternal;
  out.normal = T.rotation * normal;
  out.u_min = T.scale * u_min;
  out.u_max = T.scale * u_max;
  out.v_min = T.scale * v_min;
  out.v_max = T.scale * v_max;
  return out;
}

nlohmann::json ChestRoi::ToJson() const {
  auto v = [](const Eigen::Vector3d& a) { return nlohmann::json::array({a.x(), a.y(), a.z()}); };
  return {{"origin", v(origin)}, {"lateral", v(lateral)},        {"sternal", v(sternal)},
          {"normal", v(normal)}, {"u_range_mm", {u_min, u_max}}, {"v_range_mm", {v_min, v_max}}};
}

ChestRoi ComputeChestRoi(const LandmarkSet& landmarks, const ChestRoiOptions& options,
                         const std::string& what) {
  std::string why;
  if (!options.IsValid(&why)) ThrowUsage(why);
  landmarks.Validate(what);
  const Eigen::Vector3d notch = landmarks.Position(options.notch_label, what);
  const Eigen::Vector3d xiphoid = landmarks.Position(options.xiphoid_label, what);
  const Eigen::Vector3d cartilage = landmarks.Position(options.cartilage_label, what);

  ChestRoi roi;
  roi.origin = notch;
  // The sternal line: notch to xiphoid.
  const Eigen::Vector3d along = xiphoid - notch;
  const double length = along.norm();
  if (length < 1.0) {
    ThrowBadInput(what, "'" + options.notch_label + "' and '" + options.xiphoid_label + "' are " +
                            std::to_string(length) + " mm apart; the sternal line needs them >= 1 mm apart");
  }
  roi.sternal = along / length;
  // The lateral axis: perpendicular to the sternal line, through the cartilage (or level, with a hint).
  const Eigen::Vector3d c = cartilage - notch;
  Eigen::Vector3d off_line = c - c.dot(roi.sternal) * roi.sternal;
  if (options.anterior_hint.norm() > 0.0) {
    Eigen::Vector3d a = options.anterior_hint - options.anterior_hint.dot(roi.sternal) * roi.sternal;
    if (a.norm() < 1e-6 * options.anterior_hint.norm()) {
      ThrowUsage("the anterior hint is parallel to the sternal line of " + what);
    }
    a.normalize();
    off_line -= off_line.dot(a) * a;
  }
  const double half_width = off_line.norm();
  if (half_width < 1.0) {
    ThrowBadInput(what, "'" + options.cartilage_label + "' lies " + std::to_string(half_width) +
                            " mm from the sternal line; it must be off the line to bound the ROI's width");
  }
  roi.lateral = off_line / half_width;
  roi.normal = roi.sternal.cross(roi.lateral).normalized();
  roi.u_min = -(half_width + options.lateral_margin_mm);
  roi.u_max = half_width + options.lateral_margin_mm;
  roi.v_min = -options.superior_margin_mm;
  roi.v_max = length + options.inferior_margin_mm;
  return roi;
}

}  // namespace pectus
