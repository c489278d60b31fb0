#include "datasets/chest_surface.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "shape/core/error.h"
#include "shape/core/geometry.h"

namespace pectus::datasets {
namespace {

// Deepest inward displacement of a depression shape along its lateral axis (b = 0 maximises the profile).
double DeepestDisplacement(const formula::PectusShape& e) {
  const double reach = 4.0 * e.sigma_a * (1.0 + std::abs(e.asymmetry));
  double best = -1e300, best_a = 0.0;
  const int n = 2000;
  auto at = [&](double a) {
    const double sigma = e.sigma_a * (1.0 + e.asymmetry * std::tanh(a / (0.3 * e.sigma_a)));
    const double q2 = (a / sigma) * (a / sigma);
    const double g = e.cup ? std::exp(-0.5 * q2 * q2) : std::exp(-0.5 * q2);
    return g * (e.amplitude - e.tan_torsion * a);
  };
  for (int i = 0; i <= n; ++i) {
    const double a = -reach + 2.0 * reach * i / n;
    const double d = at(a);
    if (d > best) best = d, best_a = a;
  }
  // Golden-section refinement around the best sample.
  double lo = best_a - 2.0 * reach / n, hi = best_a + 2.0 * reach / n;
  const double r = (std::sqrt(5.0) - 1.0) / 2.0;
  for (int i = 0; i < 60; ++i) {
    const double a1 = hi - r * (hi - lo), a2 = lo + r * (hi - lo);
    if (at(a1) > at(a2)) {
      hi = a2;
    } else {
      lo = a1;
    }
  }
  return std::max(best, at(0.5 * (lo + hi)));
}

}  // namespace

formula::PectusShape MakePectusShape(const ChestParameters& p) {
  const PectusParameters& q = p.pectus;
  formula::PectusShape e;
  if (q.depth_mm <= 0.0) return e;
  e.active = true;
  e.cup = q.type == PectusType::kCup;
  e.tan_torsion = std::tan(q.torsion_deg * kDegree);
  e.half_width = 0.5 * p.width_mm;
  e.xi_centre = q.centre_x_mm / e.half_width;
  e.length = p.sternal_length_mm;
  e.s_centre = q.centre_y_mm / p.sternal_length_mm;
  e.cos_axis = std::cos(q.axis_deg * kDegree);
  e.sin_axis = std::sin(q.axis_deg * kDegree);
  e.sigma_a = q.width_mm > 0.0 ? q.width_mm : (e.cup ? 0.075 : 0.12) * p.width_mm;
  e.sigma_b = q.height_mm > 0.0 ? q.height_mm : (e.cup ? 0.10 : 0.22) * p.sternal_length_mm;
  e.asymmetry = q.asymmetry;
  // The deepest displacement grows monotonically with the amplitude: bisect for depth_mm.
  e.amplitude = 0.0;
  if (DeepestDisplacement(e) >= q.depth_mm) return e;  // torsion alone is that deep
  double lo = 0.0, hi = q.depth_mm;
  for (int i = 0; i < 80; ++i) {
    e.amplitude = 0.5 * (lo + hi);
    (DeepestDisplacement(e) < q.depth_mm ? lo : hi) = e.amplitude;
  }
  e.amplitude = 0.5 * (lo + hi);
  return e;
}

ChestSurface::ChestSurface(const ChestParameters& parameters, Layer layer, double breathing_mm)
    : parameters_(parameters), layer_(layer) {
  std::string why;
  if (!parameters_.IsValid(&why)) ThrowUsage("chest parameters: " + why);
  if (!std::isfinite(breathing_mm) || std::abs(breathing_mm) > 30.0) {
    ThrowUsage("breathing displacement must be within [-30, 30] mm");
  }
  const ChestParameters& p = parameters_;
  model_.W = p.width_mm;
  model_.D = p.depth_mm;
  model_.L = p.sternal_length_mm;
  model_.recession = p.costal_recession_mm;
  model_.ridge = p.costal_ridge_mm;
  model_.tissue = p.soft_tissue_mm;
  model_.pectoral = p.pectoral_mm;
  model_.breast = p.breast_mm;
  model_.groove = p.sternal_groove_mm;
  model_.concavity = p.concavity_mm;
  model_.notch = p.notch_mm;
  model_.clavicle = p.clavicle_mm;
  model_.pectus = MakePectusShape(p);
  model_.skin = layer == Layer::kSkin;
  model_.breathing = breathing_mm;
  Bind();
}

ChestSurface::ChestSurface(const ChestSurface& other)
    : parameters_(other.parameters_), layer_(other.layer_), model_(other.model_) {
  Bind();
}

ChestSurface& ChestSurface::operator=(const ChestSurface& other) {
  parameters_ = other.parameters_;
  layer_ = other.layer_;
  model_ = other.model_;
  Bind();
  return *this;
}

void ChestSurface::Bind() {
  model_.detail =
      parameters_.detail_mm.size() == kDetailCoefficients ? parameters_.detail_mm.data() : nullptr;
}

Eigen::Vector3d ChestSurface::SubjectPosition(double u, double v) const {
  const formula::Vec3T<double> p = formula::ChestPoint<double>(model_, u, v);
  return {p.x, p.y, p.z};
}

Eigen::Vector3d ChestSurface::Position(double u, double v) const {
  return parameters_.T_scan_subject * SubjectPosition(u, v).cwiseProduct(parameters_.growth);
}

SurfacePoint ChestSurface::Evaluate(double u, double v) const {
  const formula::Vec3T<Dual2> p = formula::ChestPoint<Dual2>(model_, Dual2(u, 1.0, 0.0), Dual2(v, 0.0, 1.0));
  const Eigen::Vector3d& g = parameters_.growth;
  const Eigen::Matrix3d R = parameters_.T_scan_subject.linear();
  SurfacePoint s;
  s.position = parameters_.T_scan_subject * Eigen::Vector3d(p.x.v * g.x(), p.y.v * g.y(), p.z.v * g.z());
  s.d_du = R * Eigen::Vector3d(p.x.du * g.x(), p.y.du * g.y(), p.z.du * g.z());
  s.d_dv = R * Eigen::Vector3d(p.x.dv * g.x(), p.y.dv * g.y(), p.z.dv * g.z());
  s.normal = s.d_du.cross(s.d_dv).normalized();
  return s;
}

Eigen::Vector2d ChestSurface::GuessParameters(const Eigen::Vector3d& x) const {
  const Eigen::Vector3d q = (parameters_.T_scan_subject.inverse() * x).cwiseQuotient(parameters_.growth);
  const double s = std::clamp(q.y() / model_.L + formula::kSNotch, (kVMin - kVReference) / formula::kSpan,
                              (kVMax - kVReference) / formula::kSpan);
  const double alpha = 1.0 + 0.02 * s - 0.10 * s * s;
  const double beta = 1.0 - 0.05 * s - 0.30 * s * s;
  const double theta = std::atan2(q.x() / (0.5 * model_.W * alpha), q.z() / (0.5 * model_.D * beta));
  return {std::clamp(theta / (std::numbers::pi / 2.0), kUMin, kUMax), kVReference + s * formula::kSpan};
}

}  // namespace pectus::datasets
