// pectus tests: an analytic chest-like surface (the front of an elliptic cylinder with a sternal dent, a
// pectoral bump and a twist, so that no rigid motion slides it onto itself), sampled with noise.
#pragma once

#include <cmath>
#include <cstdint>
#include <random>
#include <string>
#include <tuple>
#include <vector>

#include "shape/core/geometry.h"
#include "shape/core/landmarks.h"

namespace pectus::testing {

/// The surface x = (a + d) sin(phi), y = (b + d) cos(phi), z = h (mm), phi from the front (y axis).
struct ChestSurface {
  double a = 160.0;  ///< half width (mm)
  double b = 110.0;  ///< front-to-axis depth (mm)

  /// Radial offset d(phi, h) (mm): dent, bump, twist.
  double Offset(double phi, double h) const {
    const double dent =
        -25.0 * std::exp(-phi * phi / (2 * 0.25 * 0.25) - (h - 150.0) * (h - 150.0) / (2 * 50.0 * 50.0));
    const double bump =
        8.0 * std::exp(-(phi - 0.6) * (phi - 0.6) / 0.08 - (h - 200.0) * (h - 200.0) / (2 * 40.0 * 40.0));
    const double twist = 5.0 * std::sin(2.0 * phi + 0.5) * (h / 320.0);
    return dent + bump + twist;
  }
  Eigen::Vector3d Point(double phi, double h) const {
    const double d = Offset(phi, h);
    return {(a + d) * std::sin(phi), (b + d) * std::cos(phi), h};
  }
  /// Outward unit normal (central differences of the parametrisation).
  Eigen::Vector3d Normal(double phi, double h) const {
    const double e = 1e-5;
    const Eigen::Vector3d dphi = (Point(phi + e, h) - Point(phi - e, h)) / (2 * e);
    const Eigen::Vector3d dh = (Point(phi, h + e) - Point(phi, h - e)) / (2 * e);
    Eigen::Vector3d n = dphi.cross(dh).normalized();
    const Eigen::Vector3d p = Point(phi, h);
    if (n.dot(Eigen::Vector3d(p.x(), p.y(), 0.0)) < 0.0) n = -n;
    return n;
  }
};

/// `count` points drawn uniformly in (phi, h) over [phi0, phi1] x [h0, h1] (radians, mm), moved along the
/// normal by Gaussian noise of `noise_mm`, with exact (noise-free) normals.
inline PointCloud SampleChest(int count, std::uint64_t seed, double noise_mm, double phi0 = -1.3,
                              double phi1 = 1.3, double h0 = 0.0, double h1 = 320.0) {
  ChestSurface s;
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u_phi(phi0, phi1), u_h(h0, h1);
  std::normal_distribution<double> noise(0.0, noise_mm);
  PointCloud c;
  c.positions.resize(count, 3);
  c.normals.resize(count, 3);
  for (int i = 0; i < count; ++i) {
    const double phi = u_phi(rng), h = u_h(rng);
    const Eigen::Vector3d n = s.Normal(phi, h);
    c.positions.row(i) = (s.Point(phi, h) + (noise_mm > 0.0 ? noise(rng) : 0.0) * n).transpose();
    c.normals.row(i) = n.transpose();
  }
  return c;
}

/// A rigid transform with a rotation of exactly `angle_deg` about a random axis through `centre` and a
/// translation of exactly `shift_mm` in a random direction.
inline Rigid3 RandomPose(std::mt19937_64* rng, double angle_deg, double shift_mm,
                         const Eigen::Vector3d& centre = Eigen::Vector3d::Zero()) {
  std::normal_distribution<double> g(0.0, 1.0);
  const Eigen::Vector3d axis = Eigen::Vector3d(g(*rng), g(*rng), g(*rng)).normalized();
  const Eigen::Vector3d dir = Eigen::Vector3d(g(*rng), g(*rng), g(*rng)).normalized();
  Rigid3 T = Rigid3::Identity();
  T.linear() = Eigen::AngleAxisd(angle_deg * 3.14159265358979323846 / 180.0, axis).toRotationMatrix();
  T.translation() = centre - T.linear() * centre + shift_mm * dir;
  return T;
}

/// Applies T to positions and normals.
inline PointCloud Transformed(const PointCloud& c, const Rigid3& T) {
  PointCloud out = c;
  for (Eigen::Index i = 0; i < c.size(); ++i) {
    out.positions.row(i) = (T * Eigen::Vector3d(c.positions.row(i).transpose())).transpose();
    if (c.has_normals()) out.normals.row(i) = (T.linear() * c.normals.row(i).transpose()).transpose();
  }
  return out;
}

/// Five landmarks on the chest (notch, xiphoid, both nipples, umbilicus) moved by `T` and disturbed by
/// Gaussian noise of `noise_mm` per axis (seeded; no noise when noise_mm is 0).
inline LandmarkSet ChestLandmarks(const Similarity3& T = {}, double noise_mm = 0.0, std::uint64_t seed = 0) {
  const ChestSurface s;
  const std::vector<std::tuple<std::string, double, double>> where = {{"notch", 0.0, 300.0},
                                                                      {"xiphoid", 0.0, 130.0},
                                                                      {"nipple_l", -0.6, 200.0},
                                                                      {"nipple_r", 0.6, 205.0},
                                                                      {"umbilicus", 0.05, 20.0}};
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g(0.0, noise_mm);
  LandmarkSet set;
  for (const auto& [label, phi, h] : where) {
    Eigen::Vector3d p = T * s.Point(phi, h);
    if (noise_mm > 0.0) p += Eigen::Vector3d(g(rng), g(rng), g(rng));
    set.items.push_back({label, p, ""});
  }
  return set;
}

}  // namespace pectus::testing
