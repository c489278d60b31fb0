#include "planner_plugin/ribcage/chest_shell.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <numbers>

#include "shape/core/error.h"

namespace pectus::planner {

SmoothProfile::SmoothProfile(std::vector<std::pair<double, double>> points) : points_(std::move(points)) {
  if (points_.size() < 2) ThrowFailure("smooth profile: at least two control points are needed");
  for (std::size_t i = 1; i < points_.size(); ++i) {
    if (!(points_[i].first > points_[i - 1].first)) ThrowFailure("smooth profile: t must increase strictly");
  }
  const std::size_t n = points_.size();
  slopes_.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t a = i == 0 ? 0 : i - 1, b = i + 1 == n ? n - 1 : i + 1;
    slopes_[i] = (points_[b].second - points_[a].second) / (points_[b].first - points_[a].first);
  }
}

double SmoothProfile::operator()(double t) const {
  if (t <= points_.front().first) return points_.front().second;
  if (t >= points_.back().first) return points_.back().second;
  const auto it = std::upper_bound(points_.begin(), points_.end(), t,
                                   [](double v, const std::pair<double, double>& p) { return v < p.first; });
  const std::size_t i = static_cast<std::size_t>(it - points_.begin()) - 1;
  const double h = points_[i + 1].first - points_[i].first, s = (t - points_[i].first) / h;
  const double h00 = 2 * s * s * s - 3 * s * s + 1, h10 = s * s * s - 2 * s * s + s;
  const double h01 = -2 * s * s * s + 3 * s * s, h11 = s * s * s - s * s;
  return h00 * points_[i].second + h10 * h * slopes_[i] + h01 * points_[i + 1].second +
         h11 * h * slopes_[i + 1];
}

ChestShell::ChestShell()
    : ChestShell(0.0, 0.0, SmoothProfile({{0.0, 1.0}, {1.0, 1.0}}), SmoothProfile({{0.0, 1.0}, {1.0, 1.0}})) {
}

ChestShell::ChestShell(double sternum_tilt_rad, double sternum_half_thickness, SmoothProfile half_width,
                       SmoothProfile half_depth)
    : tan_tilt_(std::tan(sternum_tilt_rad)),
      front_offset_(sternum_half_thickness / std::cos(sternum_tilt_rad)),
      half_width_(std::move(half_width)),
      half_depth_(std::move(half_depth)) {}

double ChestShell::SternumAnteriorY(double z) const { return z * tan_tilt_; }

double ChestShell::CentreY(double z) const { return SternumAnteriorY(z) + front_offset_ + HalfDepth(z); }

Eigen::Vector3d ChestShell::Point(double phi, double z) const {
  const double a = HalfWidth(z), b = HalfDepth(z);
  const double pull = kPosteriorPull * b *
                      std::exp(-std::pow(std::remainder(phi, 2 * std::numbers::pi) / kPosteriorPullWidth, 2));
  return {a * std::sin(phi), CentreY(z) + b * std::cos(phi) - pull, z};
}

Eigen::Vector3d ChestShell::Normal(double phi, double z) const {
  const double h = 1e-4;
  const Eigen::Vector3d d_phi = (Point(phi + h, z) - Point(phi - h, z)) / (2 * h);
  const Eigen::Vector3d d_z = (Point(phi, z + 0.1) - Point(phi, z - 0.1)) / 0.2;
  Eigen::Vector3d n = d_phi.cross(d_z).normalized();
  const Eigen::Vector3d p = Point(phi, z);
  if (n.dot(Eigen::Vector3d(p.x(), p.y() - CentreY(z), 0.0)) < 0) n = -n;
  return n;
}

double ChestShell::PhiOf(const Eigen::Vector3d& p) const {
  const double a = HalfWidth(p.z()), b = HalfDepth(p.z());
  double phi = std::atan2(p.x() / a, (p.y() - CentreY(p.z())) / b);
  if (phi < 0) phi += 2 * std::numbers::pi;
  return phi;
}

double ChestShell::AnteriorPhiAtX(double x, double z) const {
  return std::numbers::pi - std::asin(std::clamp(x / HalfWidth(z), -1.0, 1.0));
}

double ChestShell::PosteriorPhiAtX(double x, double z) const {
  return std::asin(std::clamp(x / HalfWidth(z), -1.0, 1.0));
}

}  // namespace pectus::planner
