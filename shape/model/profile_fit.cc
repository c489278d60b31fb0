#include "shape/model/profile_fit.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

#include "shape/core/enum_names.h"
#include "shape/core/error.h"

namespace pectus {
namespace {

// Legendre polynomials P_0..P_d at s in [-1, 1] (Bonnet's recursion).
void Legendre(double s, int degree, double* out) {
  out[0] = 1.0;
  if (degree >= 1) out[1] = s;
  for (int k = 2; k <= degree; ++k) out[k] = ((2 * k - 1) * s * out[k - 1] - (k - 1) * out[k - 2]) / k;
}

// The four non-zero uniform cubic B-splines at local coordinate r in [0, 1] of an interval.
void CubicBSpline(double r, double* b) {
  const double r2 = r * r, r3 = r2 * r, q = 1.0 - r;
  b[0] = q * q * q / 6.0;
  b[1] = (3.0 * r3 - 6.0 * r2 + 4.0) / 6.0;
  b[2] = (-3.0 * r3 + 3.0 * r2 + 3.0 * r + 1.0) / 6.0;
  b[3] = r3 / 6.0;
}

}  // namespace

constexpr EnumNames<ProfileFitKind, 2> kProfileFitNames{
    {{ProfileFitKind::kPolynomial, "polynomial"}, {ProfileFitKind::kSmoothingSpline, "spline"}}};

ProfileFitKind ParseProfileFitKind(const std::string& text) {
  // "poly" is accepted as a short form of "polynomial".
  return ParseEnum(kProfileFitNames, text == "poly" ? "polynomial" : text, [&] {
    return "profile fit '" + text + "' is not " + ListEnumNames(kProfileFitNames, "'", ", ", " or ");
  });
}

std::string ToString(ProfileFitKind kind) { return EnumToString(kProfileFitNames, kind, "spline"); }

bool ProfileFitOptions::IsValid(std::string* why) const {
  auto fail = [&](const std::string& m) {
    if (why != nullptr) *why = m;
    return false;
  };
  if (polynomial_degree < 1 || polynomial_degree > 20) return fail("polynomial degree must be in [1, 20]");
  if (!(knot_spacing_mm > 0.0) || !std::isfinite(knot_spacing_mm)) return fail("knot spacing must be > 0 mm");
  if (!(smoothing >= 0.0) || !std::isfinite(smoothing)) return fail("spline smoothing must be >= 0");
  if (penalty_order != 2 && penalty_order != 3) return fail("spline penalty order must be 2 or 3");
  return true;
}

double ProfileCurve::Evaluate(double t) const {
  if (kind_ == ProfileFitKind::kPolynomial) {
    const int d = static_cast<int>(coefficients_.size()) - 1;
    double p[21];
    Legendre((2.0 * t - lo_ - hi_) / (hi_ - lo_), d, p);
    return Eigen::Map<const Eigen::VectorXd>(p, d + 1).dot(coefficients_);
  }
  const Eigen::Index intervals = coefficients_.size() - 3;
  const double x = (t - lo_) / step_;
  const Eigen::Index k = std::clamp<Eigen::Index>(static_cast<Eigen::Index>(std::floor(x)), 0, intervals - 1);
  double b[4];
  CubicBSpline(x - static_cast<double>(k), b);
  return b[0] * coefficients_[k] + b[1] * coefficients_[k + 1] + b[2] * coefficients_[k + 2] +
         b[3] * coefficients_[k + 3];
}

double ProfileCurve::Slope(double t) const {
  const double h = 1e-4 * (hi_ - lo_);
  const double a = std::max(lo_, t - h), b = std::min(hi_, t + h);
  return (Evaluate(b) - Evaluate(a)) / (b - a);
}

double ProfileCurve::operator()(double t) const {
  if (t < lo_) return Evaluate(lo_) + (t - lo_) * Slope(lo_);
  if (t > hi_) return Evaluate(hi_) + (t - hi_) * Slope(hi_);
  return Evaluate(t);
}

double ProfileCurve::DistanceToData(double t) const {
  if (sorted_t_.empty()) return std::numeric_limits<double>::infinity();
  auto it = std::lower_bound(sorted_t_.begin(), sorted_t_.end(), t);
  double d = std::numeric_limits<double>::infinity();
  if (it != sorted_t_.end()) d = *it - t;
  if (it != sorted_t_.begin()) d = std::min(d, t - *(it - 1));
  return d;
}

void ProfileCurve::DistancesToDataOnEachSide(double t, double* below, double* above) const {
  *below = *above = std::numeric_limits<double>::infinity();
  auto it = std::lower_bound(sorted_t_.begin(), sorted_t_.end(), t);
  if (it != sorted_t_.end()) *above = *it - t;
  if (it != sorted_t_.begin()) *below = t - *(it - 1);
  if (it != sorted_t_.end() && *it == t) *below = 0.0;
}

ProfileCurve FitProfile(const Eigen::VectorXd& t, const Eigen::VectorXd& y, double t_min, double t_max,
                        const ProfileFitOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) ThrowUsage(why);
  ProfileCurve curve;
  const Eigen::Index n = t.size();
  if (n == 0 || y.size() != n) return curve;
  curve.kind_ = options.kind;
  curve.sorted_t_.assign(t.data(), t.data() + n);
  std::sort(curve.sorted_t_.begin(), curve.sorted_t_.end());
  curve.lo_ = std::min(t_min, curve.sorted_t_.front());
  curve.hi_ = std::max(t_max, curve.sorted_t_.back());
  if (!(curve.hi_ > curve.lo_)) return curve;
  // Distinct abscissae (0.01 mm apart) decide whether the fit is determined.
  Eigen::Index distinct = 1;
  for (std::size_t k = 1; k < curve.sorted_t_.size(); ++k) {
    if (curve.sorted_t_[k] - curve.sorted_t_[k - 1] > 1e-2) ++distinct;
  }

  if (options.kind == ProfileFitKind::kPolynomial) {
    const int d = options.polynomial_degree;
    if (distinct < d + 1) return curve;
    // Least squares in the Legendre basis on [lo, hi] mapped to [-1, 1], solved by QR.
    Eigen::MatrixXd A(n, d + 1);
    double p[21];
    for (Eigen::Index k = 0; k < n; ++k) {
      Legendre((2.0 * t[k] - curve.lo_ - curve.hi_) / (curve.hi_ - curve.lo_), d, p);
      A.row(k) = Eigen::Map<const Eigen::RowVectorXd>(p, d + 1);
    }
    curve.coefficients_ = A.colPivHouseholderQr().solve(y);
  } else {
    if (distinct < (options.smoothing > 0.0 ? options.penalty_order : 4)) return curve;
    // P-spline (Eilers & Marx 1996): (B'B / n + smoothing * D'D / nb) a = B'y / n, D = differences of
    // order q.
    const auto intervals = std::max<Eigen::Index>(
        1, static_cast<Eigen::Index>(std::ceil((curve.hi_ - curve.lo_) / options.knot_spacing_mm)));
    curve.step_ = (curve.hi_ - curve.lo_) / static_cast<double>(intervals);
    const Eigen::Index nb = intervals + 3;
    Eigen::MatrixXd normal = Eigen::MatrixXd::Zero(nb, nb);
    Eigen::VectorXd rhs = Eigen::VectorXd::Zero(nb);
    double b[4];
    for (Eigen::Index k = 0; k < n; ++k) {
      const double x = (t[k] - curve.lo_) / curve.step_;
      const Eigen::Index c =
          std::clamp<Eigen::Index>(static_cast<Eigen::Index>(std::floor(x)), 0, intervals - 1);
      CubicBSpline(x - static_cast<double>(c), b);
      for (int r = 0; r < 4; ++r) {
        rhs[c + r] += b[r] * y[k] / static_cast<double>(n);
        for (int s = 0; s < 4; ++s) normal(c + r, c + s) += b[r] * b[s] / static_cast<double>(n);
      }
    }
    // Difference penalty of order q: rows (1, -2, 1) or (-1, 3, -3, 1).
    const int q = options.penalty_order;
    const double d2[3] = {1.0, -2.0, 1.0}, d3[4] = {-1.0, 3.0, -3.0, 1.0};
    const double* dj = q == 2 ? d2 : d3;
    const double weight = options.smoothing / static_cast<double>(nb);
    for (Eigen::Index j = 0; j + q < nb; ++j) {
      for (int r = 0; r <= q; ++r) {
        for (int s = 0; s <= q; ++s) normal(j + r, j + s) += weight * dj[r] * dj[s];
      }
    }
    // A tiny ridge keeps the system definite where a basis has neither data nor penalty (smoothing 0).
    normal.diagonal().array() += 1e-12 * normal.diagonal().maxCoeff();
    curve.coefficients_ = normal.ldlt().solve(rhs);
  }
  if (!curve.coefficients_.allFinite()) return curve;
  curve.valid_ = true;
  double sum = 0.0;
  for (Eigen::Index k = 0; k < n; ++k) sum += std::pow(curve.Evaluate(t[k]) - y[k], 2);
  curve.rms_ = std::sqrt(sum / static_cast<double>(n));
  return curve;
}

}  // namespace pectus
