#include "datasets/internal/tracker_error.h"

#include <Eigen/Geometry>
#include <cmath>

#include "datasets/seeding.h"
#include "shape/core/geometry.h"

namespace pectus::datasets::internal {
namespace {

Rigid3 ErrorOf(const Eigen::Vector3d& axis, double angle_deg, const Eigen::Vector3d& shift,
               const Eigen::Vector3d& pivot) {
  Rigid3 error = Rigid3::Identity();
  error.linear() = Eigen::AngleAxisd(angle_deg * kDegree, axis).toRotationMatrix();
  error.translation() = pivot - error.linear() * pivot + shift;
  return error;
}

}  // namespace

double RmsDisplacement(const Rigid3& T, const Points3& points) {
  if (points.rows() == 0) return 0.0;
  double sum = 0.0;
  for (Eigen::Index i = 0; i < points.rows(); ++i) {
    const Eigen::Vector3d p = points.row(i).transpose();
    sum += (T * p - p).squaredNorm();
  }
  return std::sqrt(sum / static_cast<double>(points.rows()));
}

TrackerError DrawTrackerError(const ScanOptions& o, const Eigen::Vector3d& pivot, const Points3& true_points,
                              std::mt19937_64* rng) {
  const Eigen::Vector3d axis = RandomUnit(rng);
  const Eigen::Vector3d direction = RandomUnit(rng);
  TrackerError e;
  e.angle_deg = o.tracker_deg;
  e.shift_mm = o.tracker_mm;
  double skin_mm = o.tracker_skin_mm;
  if (o.tracker_draw == TrackerDraw::kUniform) {
    std::uniform_real_distribution<double> uniform(0.0, 1.0);
    e.angle_deg *= uniform(*rng);
    e.shift_mm *= uniform(*rng);
    skin_mm *= uniform(*rng);
  }
  e.error = ErrorOf(axis, e.angle_deg, e.shift_mm * direction, pivot);
  if (o.tracker_skin_mm > 0.0 && true_points.rows() > 0 && (e.angle_deg > 0.0 || e.shift_mm > 0.0)) {
    // Scale angle and shift together by s so that the RMS displacement is skin_mm: it grows with s (for
    // angles below 90 degrees), so bracket s and bisect to round-off.
    auto rms = [&](double s) {
      return RmsDisplacement(ErrorOf(axis, s * e.angle_deg, s * e.shift_mm * direction, pivot), true_points);
    };
    double lo = 0.0, hi = 1.0;
    while (rms(hi) < skin_mm && hi * e.angle_deg < 90.0) {
      lo = hi;
      hi *= 2.0;
    }
    for (int i = 0; i < 100 && hi - lo > 1e-15 * hi; ++i) {
      const double mid = 0.5 * (lo + hi);
      (rms(mid) < skin_mm ? lo : hi) = mid;
    }
    const double s = 0.5 * (lo + hi);
    e.angle_deg *= s;
    e.shift_mm *= s;
    e.error = ErrorOf(axis, e.angle_deg, e.shift_mm * direction, pivot);
  }
  e.skin_rms_mm = RmsDisplacement(e.error, true_points);
  return e;
}

}  // namespace pectus::datasets::internal
