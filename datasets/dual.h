// pectus datasets: a two-variable forward-mode dual number, so that one templated formula of the chest
// surface gives its value and its exact first derivatives with respect to the parameters (u, v).
#pragma once

#include <cmath>

namespace pectus::datasets {

/// A value with its partial derivatives with respect to two variables (u, v): f, df/du, df/dv.
/// Arithmetic follows the chain rule exactly (no finite differences).
struct Dual2 {
  double v = 0.0;   ///< value
  double du = 0.0;  ///< partial derivative with respect to u
  double dv = 0.0;  ///< partial derivative with respect to v

  constexpr Dual2() = default;
  constexpr Dual2(double value) : v(value) {}  // NOLINT: constants promote implicitly
  constexpr Dual2(double value, double d_u, double d_v) : v(value), du(d_u), dv(d_v) {}
};

inline Dual2 operator+(Dual2 a, Dual2 b) { return {a.v + b.v, a.du + b.du, a.dv + b.dv}; }
inline Dual2 operator-(Dual2 a, Dual2 b) { return {a.v - b.v, a.du - b.du, a.dv - b.dv}; }
inline Dual2 operator-(Dual2 a) { return {-a.v, -a.du, -a.dv}; }
inline Dual2 operator*(Dual2 a, Dual2 b) {
  return {a.v * b.v, a.du * b.v + a.v * b.du, a.dv * b.v + a.v * b.dv};
}
inline Dual2 operator*(double s, Dual2 a) { return {s * a.v, s * a.du, s * a.dv}; }
inline Dual2 operator*(Dual2 a, double s) { return {s * a.v, s * a.du, s * a.dv}; }
inline Dual2 operator/(Dual2 a, double s) { return {a.v / s, a.du / s, a.dv / s}; }
inline Dual2 operator/(Dual2 a, Dual2 b) {
  const double inv = 1.0 / b.v;
  const double q = a.v * inv;
  return {q, (a.du - q * b.du) * inv, (a.dv - q * b.dv) * inv};
}
inline Dual2 operator/(double s, Dual2 b) {
  const double q = s / b.v;
  const double slope = -q / b.v;
  return {q, slope * b.du, slope * b.dv};
}
inline Dual2 operator+(Dual2 a, double s) { return {a.v + s, a.du, a.dv}; }
inline Dual2 operator+(double s, Dual2 a) { return {a.v + s, a.du, a.dv}; }
inline Dual2 operator-(Dual2 a, double s) { return {a.v - s, a.du, a.dv}; }
inline Dual2 operator-(double s, Dual2 a) { return {s - a.v, -a.du, -a.dv}; }
inline Dual2& operator+=(Dual2& a, Dual2 b) { return a = a + b; }
inline Dual2& operator-=(Dual2& a, Dual2 b) { return a = a - b; }
inline Dual2& operator*=(Dual2& a, Dual2 b) { return a = a * b; }

/// Chain rule for f(a) with f(a.v) = value and f'(a.v) = slope.
inline Dual2 Chain(Dual2 a, double value, double slope) { return {value, slope * a.du, slope * a.dv}; }

inline Dual2 exp(Dual2 a) {
  const double e = std::exp(a.v);
  return Chain(a, e, e);
}
inline Dual2 sin(Dual2 a) { return Chain(a, std::sin(a.v), std::cos(a.v)); }
inline Dual2 cos(Dual2 a) { return Chain(a, std::cos(a.v), -std::sin(a.v)); }
inline Dual2 sqrt(Dual2 a) {
  const double s = std::sqrt(a.v);
  return Chain(a, s, 0.5 / s);
}
inline Dual2 tanh(Dual2 a) {
  const double t = std::tanh(a.v);
  return Chain(a, t, 1.0 - t * t);
}
inline Dual2 abs(Dual2 a) { return a.v < 0.0 ? -a : a; }

/// The value of a double or a Dual2 (for branches and table look-ups).
inline double ValueOf(double a) { return a; }
inline double ValueOf(const Dual2& a) { return a.v; }

}  // namespace pectus::datasets
