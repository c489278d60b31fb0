// pectus: a curve y(t) fitted to the points of one cross-section profile: a least-squares polynomial
// or a penalised cubic regression spline (P-spline, Eilers & Marx 1996), which interpolates across
// holes in the data and extrapolates beyond them (dissertation §4.3.1, Fig. 36).
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

namespace pectus {

/// Which curve a profile gets.
enum class ProfileFitKind {
  kPolynomial,       ///< least-squares polynomial of `polynomial_degree` (Legendre basis)
  kSmoothingSpline,  ///< cubic B-spline on equally spaced knots with a second-difference penalty
};

/// "polynomial" or "spline"; throws Error(kUsage) otherwise.
ProfileFitKind ParseProfileFitKind(const std::string& text);
std::string ToString(ProfileFitKind kind);

/// How a profile is fitted.
struct ProfileFitOptions {
  ProfileFitKind kind = ProfileFitKind::kSmoothingSpline;
  int polynomial_degree = 8;     ///< kPolynomial: degree in [1, 20]
  double knot_spacing_mm = 5.0;  ///< kSmoothingSpline: distance between knots (> 0, mm)
  /// kSmoothingSpline: weight of the roughness penalty, dimensionless (>= 0; > 0 if the data may have
  /// gaps wider than a knot interval). The fit minimises mean(r^2) + smoothing * mean((Dq a)^2) over
  /// the spline coefficients a (Dq: differences of order q = penalty_order), both terms in mm^2.
  double smoothing = 1e-3;
  /// kSmoothingSpline: order q of the difference penalty, 2 or 3. Where there are no data the penalty
  /// continues the curve as a polynomial of degree q - 1 (Eilers & Marx 1996, Sec. 8): q = 2 goes on
  /// linearly beyond the data, q = 3 keeps the curvature, which follows a chest's transverse curve over
  /// a hole or past the edge of a scan much better (measured in docs/model.md).
  int penalty_order = 3;

  /// False, with the reason, for a value out of range.
  bool IsValid(std::string* why) const;
};

/// A fitted profile curve. Default-constructed it is invalid (too few points to fit). Beyond the interval it
/// was fitted on, it continues linearly along its end tangents.
class ProfileCurve {
 public:
  ProfileCurve() = default;
  /// True if the fit succeeded.
  bool valid() const { return valid_; }
  /// y(t), mm. Beyond the fitted interval the curve continues linearly.
  double operator()(double t) const;
  /// Distance (mm) from t to the nearest data abscissa: 0 inside dense data, the half-width of a hole
  /// at its centre, the extrapolation distance beyond the data.
  double DistanceToData(double t) const;
  /// Distances (mm) from t to the nearest data abscissa at or below it and at or above it; infinity on
  /// a side without data (t beyond the data).
  void DistancesToDataOnEachSide(double t, double* below, double* above) const;
  /// RMS of the residuals at the data points, mm.
  double rms_residual() const { return rms_; }
  /// Number of data points fitted.
  Eigen::Index num_points() const { return static_cast<Eigen::Index>(sorted_t_.size()); }

 private:
  friend ProfileCurve FitProfile(const Eigen::VectorXd&, const Eigen::VectorXd&, double, double,
                                 const ProfileFitOptions&);
  double Evaluate(double t) const;  // inside [lo_, hi_]
  double Slope(double t) const;     // numerical, inside [lo_, hi_]
  bool valid_ = false;
  ProfileFitKind kind_ = ProfileFitKind::kSmoothingSpline;
  double lo_ = 0.0, hi_ = 0.0;  // fitted interval
  double step_ = 1.0;           // spline knot spacing (t units)
  Eigen::VectorXd coefficients_;
  std::vector<double> sorted_t_;
  double rms_ = 0.0;
};

/// Fits y(t) to the points (t_k, y_k). The curve is defined over [min(t_min, min t), max(t_max, max t)].
/// Returns an invalid curve if there are too few distinct points: fewer than degree + 1 for a
/// polynomial, fewer than 4 (or penalty_order with smoothing > 0) for a spline.
/// @param[in] t, y   #n abscissae and ordinates (mm)
/// @param[in] t_min, t_max  the interval the curve will be evaluated on
ProfileCurve FitProfile(const Eigen::VectorXd& t, const Eigen::VectorXd& y, double t_min, double t_max,
                        const ProfileFitOptions& options);

}  // namespace pectus
