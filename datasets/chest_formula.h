// pectus datasets (internal): the analytic chest surface as one templated formula, evaluated with double
// (positions) or Dual2 (positions with exact derivatives). docs/datasets.md, "The chest model", gives the
// same formula in words; keep the two in step.
#pragma once

#include <cmath>
#include <numbers>

#include "datasets/chest_parameters.h"
#include "datasets/dual.h"

namespace pectus::datasets::formula {

// Levels of the parameter v (0 bottom, 1 top). s = (v - kVReference) / kSpan is the height above the
// reference level in sternal lengths: the xiphoid is at s = -0.3, the sternal notch at s = +0.7.
inline constexpr double kVXiphoid = 0.25;
inline constexpr double kVNotch = 0.90;
inline constexpr double kSpan = kVNotch - kVXiphoid;
inline constexpr double kVReference = kVXiphoid + 0.3 * kSpan;
inline constexpr double kSNotch = 0.7;
inline constexpr double kSXiphoid = -0.3;
// Cross-section: flattened front c(theta) = cos(theta) (1 + kappa sin^2(theta)); the reference normal
// n0(theta) is the normal of the curve (kRhoX sin(theta), -kRhoY c(theta)) in (lateral, posterior)
// coordinates (nx, ny below); ChestPoint turns that into the subject frame (x left, y up, z anterior).
inline constexpr double kKappa = 0.3;
inline constexpr double kRhoX = 135.0;
inline constexpr double kRhoY = 95.0;

/// Precomputed pectus shape (see PectusParameters); amplitude solved so that the deepest point is depth_mm.
struct PectusShape {
  bool active = false;
  bool cup = false;
  double amplitude = 0.0;  // mm
  double tan_torsion = 0.0;
  double half_width = 135.0;  // W / 2, mm
  double xi_centre = 0.0;     // centre_x / (W / 2)
  double s_centre = 0.0;      // centre_y / L
  double length = 170.0;      // L, mm
  double cos_axis = 1.0, sin_axis = 0.0;
  double sigma_a = 50.0, sigma_b = 45.0;  // mm
  double asymmetry = 0.0;
};

/// Everything the formula reads, copied out of ChestParameters.
struct Model {
  double W = 270, D = 190, L = 170;
  double recession = 0, ridge = 0;
  double tissue = 0, pectoral = 0, breast = 0, groove = 0, concavity = 0, notch = 0, clavicle = 0;
  const double* detail = nullptr;  // kDetailCoefficients values or null
  PectusShape pectus;
  bool skin = true;
  double breathing = 0.0;  // mm
};

template <typename T>
struct Vec3T {
  T x, y, z;
};

/// A C^2 bump with the width and curvature of exp(-(a / w)^2) at its peak, zero for |a| >= sqrt(3) w:
/// (1 - (a / w)^2 / 3)^3. Polynomial, so that the surface costs no exponentials.
template <typename T>
inline T Bump(T a, double w) {
  const T q = a * (1.0 / w);  // the reciprocal folds to a constant: no division
  const T r = 1.0 - q * q * (1.0 / 3.0);
  if (ValueOf(r) <= 0.0) return T(0.0);
  return r * r * r;
}

/// A C^2 step from 0 (a << 0) to 1 (a >> 0) with the slope of the logistic 1 / (1 + exp(-a / w)) at
/// a = 0: the quintic smootherstep over a in [-3.75 w, 3.75 w].
template <typename T>
inline T Step(T a, double w) {
  const T x = a * (1.0 / (7.5 * w)) + 0.5;
  if (ValueOf(x) <= 0.0) return T(0.0);
  if (ValueOf(x) >= 1.0) return T(1.0);
  return x * x * x * (x * (6.0 * x - 15.0) + 10.0);
}

/// The centred cubic B-spline kernel and its slope at t in (-2, 2).
inline void CubicKernelWithSlope(double t, double* w, double* slope) {
  const double a = std::abs(t), sign = t < 0.0 ? -1.0 : 1.0;
  if (a < 1.0) {
    *w = (4.0 - 6.0 * a * a + 3.0 * a * a * a) / 6.0;
    *slope = sign * (-2.0 * a + 1.5 * a * a);
  } else {
    const double b = 2.0 - a;
    *w = b * b * b / 6.0;
    *slope = -sign * 0.5 * b * b;
  }
}

/// The detail field at (u, v) and its partial derivatives: a bicubic B-spline whose control points lie one
/// knot beyond the domain on every side (kDetailU - 3 intervals across u in [-1, 1], kDetailV - 3 up v in [0,
/// 1]).
inline void DetailWithSlopes(const double* c, double u, double v, double* value, double* d_du, double* d_dv) {
  const double hu = 2.0 / (kDetailU - 3), hv = 1.0 / (kDetailV - 3);
  const double fu = (u + 1.0) / hu, fv = v / hv;
  const int ku = static_cast<int>(std::floor(fu)), kv = static_cast<int>(std::floor(fv));
  double bu[4], su[4], bv[4], sv[4];
  for (int a = 0; a < 4; ++a) {
    CubicKernelWithSlope(fu - static_cast<double>(ku + a - 1), &bu[a], &su[a]);
    CubicKernelWithSlope(fv - static_cast<double>(kv + a - 1), &bv[a], &sv[a]);
  }
  double f = 0.0, fu_sum = 0.0, fv_sum = 0.0;
  for (int b = 0; b < 4; ++b) {
    const int j = kv + b;
    if (j < 0 || j >= kDetailV) continue;
    double row = 0.0, row_slope = 0.0;
    for (int a = 0; a < 4; ++a) {
      const int i = ku + a;
      if (i < 0 || i >= kDetailU) continue;
      row += c[j * kDetailU + i] * bu[a];
      row_slope += c[j * kDetailU + i] * su[a];
    }
    f += row * bv[b];
    fu_sum += row_slope * bv[b];
    fv_sum += row * sv[b];
  }
  *value = f;
  *d_du = fu_sum / hu;
  *d_dv = fv_sum / hv;
}

/// The detail field at (u, v) (double), or with its derivatives carried along (Dual2), by the chain rule.
inline double Detail(const double* c, double u, double v) {
  double f, fu, fv;
  DetailWithSlopes(c, u, v, &f, &fu, &fv);
  return f;
}
inline Dual2 Detail(const double* c, const Dual2& u, const Dual2& v) {
  double f, fu, fv;
  DetailWithSlopes(c, u.v, v.v, &f, &fu, &fv);
  return {f, fu * u.du + fv * v.du, fu * u.dv + fv * v.dv};
}

/// Inward displacement of the chest wall by the depression at lateral coordinate xi = sin(theta) and height
/// s.
template <typename T>
T PectusDisplacement(const PectusShape& e, T xi, T s) {
  using std::exp;
  using std::tanh;
  const T xh = e.half_width * (xi - e.xi_centre);  // mm, lateral
  const T zh = e.length * (s - e.s_centre);        // mm, vertical
  const T a = e.cos_axis * xh + e.sin_axis * zh;
  const T b = e.cos_axis * zh - e.sin_axis * xh;
  const T sigma_a = e.sigma_a * (1.0 + e.asymmetry * tanh(a / (0.3 * e.sigma_a)));
  const T qa = a / sigma_a, qb = b / e.sigma_b;
  const T r2 = qa * qa + qb * qb;
  const T g = e.cup ? exp(-0.5 * r2 * r2) : exp(-0.5 * r2);
  return g * (e.amplitude - e.tan_torsion * a);
}

/// The chest point at (u, v) in the subject frame before growth and pose (mm).
template <typename T>
Vec3T<T> ChestPoint(const Model& m, T u, T v) {
  using std::cos;
  using std::exp;
  using std::sin;
  using std::sqrt;
  const T theta = (std::numbers::pi / 2.0) * u;
  const T st = sin(theta), ct = cos(theta);
  const T c = ct * (1.0 + kKappa * st * st);
  const T dc = st * (-1.0 + kKappa * (2.0 * ct * ct - st * st));
  const T nxr = -kRhoY * dc, nyr = -kRhoX * ct;
  const T nn = sqrt(nxr * nxr + nyr * nyr);
  const T nx = nxr / nn, ny = nyr / nn;

  const T s = (v - kVReference) * (1.0 / kSpan);
  const T alpha = 1.0 + 0.02 * s - 0.10 * s * s;
  const T beta = 1.0 - 0.05 * s - 0.30 * s * s;

  // Chest wall: costal margins from the xiphoid down and out, the abdomen behind them, the depression.
  const T st2 = st * st;
  const T flank_root = 1.0 - st2 * st2;  // flank = (1 - st^4)^3: 1 in front, 0 at the mid-axillary lines
  const T flank = flank_root * flank_root * flank_root;
  const T s_margin = (kSXiphoid + 0.05) - 0.85 * sqrt(st2 + 0.0025);
  T offset = -m.recession * flank * Step(s_margin - s, 0.03) +
             m.ridge * flank * Bump(s - s_margin, 0.04) * (1.0 - Bump(st, 0.1));
  if (m.pectus.active) offset -= PectusDisplacement(m.pectus, st, s);
  if (m.breathing != 0.0) offset += m.breathing * Bump(st, 0.8) * (0.5 + 0.5 * Step(-(s + 0.1), 0.25));

  if (m.skin) {
    const T pectoral = (Bump(st - 0.45, 0.30) + Bump(st + 0.45, 0.30)) * Bump(s - 0.42, 0.32);
    const T breast = (Bump(st - 0.52, 0.17) + Bump(st + 0.52, 0.17)) * Bump(s - 0.08, 0.16);
    const T groove = Bump(st, 0.075) * Step(s + 0.32, 0.04) * Step(0.72 - s, 0.04);
    const T concavity = Bump(st, 0.28) * Bump(s - 0.05, 0.35);
    const T notch = Bump(st, 0.07) * Bump(s - 0.72, 0.05);
    const T clavicle = (Bump(st - 0.3, 0.17) + Bump(st + 0.3, 0.17)) * Bump(s - 0.76 - 0.06 * st2, 0.045);
    offset += m.tissue + m.pectoral * pectoral + m.breast * breast - m.groove * groove -
              m.concavity * concavity - m.notch * notch + m.clavicle * clavicle;
    if (m.detail) offset += Detail(m.detail, u, v);
  }
  // Subject frame: x to the subject's left, y up (superior), z out of the chest (anterior). The front of
  // the cross-section is at z = +D beta c / 2; the reference normal's anterior component is -ny.
  return {0.5 * m.W * alpha * st + offset * nx, (s - kSNotch) * m.L, 0.5 * m.D * beta * c - offset * ny};
}

}  // namespace pectus::datasets::formula
