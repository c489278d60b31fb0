// pectus planner: the generic chest shell, the smooth surface on which the centre lines of the ribs and
// costal cartilages lie (dissertation §4.1.1: a generic ribcage with anatomical proportions).
#pragma once

#include <Eigen/Core>
#include <utility>
#include <vector>

namespace pectus::planner {

/// A smooth function of one variable through control points (t_i, v_i): cubic Hermite with
/// Catmull-Rom tangents (one-sided at the ends), constant outside [t_0, t_n].
class SmoothProfile {
 public:
  SmoothProfile() = default;
  /// @param[in] points  (t, value) pairs with strictly increasing t; at least two
  explicit SmoothProfile(std::vector<std::pair<double, double>> points);
  double operator()(double t) const;

 private:
  std::vector<std::pair<double, double>> points_;
  std::vector<double> slopes_;
};

/// The chest shell in the ribcage frame (LPS: x to the patient's left, y posterior, z superior, mm; the
/// origin at the sternal notch on the anterior surface of the manubrium). At height z its section is an
/// ellipse of half-width a(z) and half-depth b(z) centred at (0, y_c(z)), pulled forward near the
/// posterior midline where the ribs reach the vertebrae:
///   x = a(z) sin(phi),  y = y_c(z) + b(z) cos(phi) - g b(z) exp(-(phi / sigma)^2),
/// phi = 0 at the back, pi at the front; phi in (0, pi) is the left side, (pi, 2 pi) the right. Its
/// front (phi = pi) follows the mid-thickness of the sternum, so no rib lies in front of the sternum.
class ChestShell {
 public:
  /// @param[in] sternum_tilt_rad        forward lean of the sternum from vertical (lower end anterior)
  /// @param[in] sternum_half_thickness  mm, from the sternum's anterior surface to the shell's front
  /// @param[in] half_width              a(z), mm, as a profile in z
  /// @param[in] half_depth              b(z), mm, as a profile in z
  /// A placeholder shell (a unit cylinder); assign a real one before use.
  ChestShell();
  ChestShell(double sternum_tilt_rad, double sternum_half_thickness, SmoothProfile half_width,
             SmoothProfile half_depth);

  double HalfWidth(double z) const { return half_width_(z); }
  double HalfDepth(double z) const { return half_depth_(z); }
  /// y of the ellipse centre at height z, mm.
  double CentreY(double z) const;
  /// y of the anterior surface of the sternum (extended as a line above and below it) at height z, mm.
  double SternumAnteriorY(double z) const;
  /// The shell point at (phi, z).
  Eigen::Vector3d Point(double phi, double z) const;
  /// The unit outward normal at (phi, z).
  Eigen::Vector3d Normal(double phi, double z) const;
  /// The angle phi whose elliptic ray passes through p (left side for p.x > 0), ignoring the posterior
  /// pull (which vanishes on the anterior half).
  double PhiOf(const Eigen::Vector3d& p) const;
  /// The anterior-half angle phi in [pi/2, pi] (left side) at which the shell reaches lateral x at z.
  double AnteriorPhiAtX(double x, double z) const;
  /// The posterior-half angle phi in (0, pi/2] at which the shell reaches lateral x at z.
  double PosteriorPhiAtX(double x, double z) const;

  static constexpr double kPosteriorPull = 0.8;  ///< g: the pull at the posterior midline, in units of b
  static constexpr double kPosteriorPullWidth = 0.45;  ///< sigma, rad

 private:
  double tan_tilt_;
  double front_offset_;
  SmoothProfile half_width_, half_depth_;
};

}  // namespace pectus::planner
