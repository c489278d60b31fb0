// pectus datasets: the analytic chest surface of one subject, evaluated exactly at parameters (u, v).
#pragma once

#include <Eigen/Core>

#include "datasets/chest_formula.h"
#include "datasets/chest_parameters.h"

namespace pectus::datasets {

/// Which of the two surfaces of a subject.
enum class Layer {
  kSkin,       ///< what the scanner sees: the chest wall plus the soft tissue
  kChestWall,  ///< the outer surface of the ribcage and sternum (what CT parameters measure)
};

/// Parameter domain: u in [-1, 1] from the right mid-axillary line (u = -1) across the front (u = 0, the
/// midline) to the left (u = +1); v in [0, 1] from below the xiphoid (v = 0) to above the sternal notch
/// (v = 1). The xiphoid is at v = kVXiphoid, the notch at v = kVNotch on the midline.
inline constexpr double kUMin = -1.0;
inline constexpr double kUMax = 1.0;
inline constexpr double kVMin = 0.0;
inline constexpr double kVMax = 1.0;
inline constexpr double kVXiphoid = formula::kVXiphoid;
inline constexpr double kVNotch = formula::kVNotch;
/// The reference level (30 % of the sternum above the xiphoid) where W and D are defined and a depression
/// is centred by default.
inline constexpr double kVReference = formula::kVReference;

/// A surface point with its exact first derivatives.
struct SurfacePoint {
  Eigen::Vector3d position;  ///< mm, scan frame
  Eigen::Vector3d d_du;      ///< dposition/du, mm per unit u
  Eigen::Vector3d d_dv;      ///< dposition/dv, mm per unit v
  Eigen::Vector3d normal;    ///< unit, outward (d_du x d_dv normalised: anterior / lateral)
};

/// One subject's surface: x(u, v) = T_scan_subject (growth .* (wall(u, v) + offset(u, v) n0(u))), exact and
/// smooth (C^2) on the whole domain and beyond it (the formula extrapolates smoothly).
///
/// The surface is affine in the linear part of the parameters (LinearPart), so for fixed (u, v) the point
/// is mean + sum_k b_k mode_k(u, v) for any population built on them.
class ChestSurface {
 public:
  /// @param[in] parameters    must be valid (throws Error(kUsage) with the reason otherwise)
  /// @param[in] layer         skin (default) or chest wall
  /// @param[in] breathing_mm  displacement of the breathing field (0: the reference state), mm
  explicit ChestSurface(const ChestParameters& parameters, Layer layer = Layer::kSkin,
                        double breathing_mm = 0.0);
  ChestSurface(const ChestSurface& other);
  ChestSurface& operator=(const ChestSurface& other);

  /// Position at (u, v), mm, scan frame.
  Eigen::Vector3d Position(double u, double v) const;
  /// Position, exact derivatives and unit normal at (u, v).
  SurfacePoint Evaluate(double u, double v) const;
  /// Position at (u, v) in the subject frame (no growth, no pose), mm.
  Eigen::Vector3d SubjectPosition(double u, double v) const;

  /// A starting guess of the parameters (u, v) of the surface point nearest a point (mm, scan frame), from
  /// the elliptic cross-section; clamped to the domain.
  Eigen::Vector2d GuessParameters(const Eigen::Vector3d& x) const;

  const ChestParameters& parameters() const { return parameters_; }
  Layer layer() const { return layer_; }
  double breathing_mm() const { return model_.breathing; }
  /// The amplitude of the depression's profile that makes its deepest point pectus.depth_mm deep, mm.
  double pectus_amplitude_mm() const { return model_.pectus.amplitude; }

  /// The same subject's other layer, or another breathing state.
  ChestSurface WithLayer(Layer layer) const { return ChestSurface(parameters_, layer, model_.breathing); }
  ChestSurface WithBreathing(double breathing_mm) const {
    return ChestSurface(parameters_, layer_, breathing_mm);
  }

 private:
  void Bind();
  ChestParameters parameters_;
  Layer layer_;
  formula::Model model_;
};

/// The depression's shape with its amplitude solved (exposed for tests).
formula::PectusShape MakePectusShape(const ChestParameters& parameters);

}  // namespace pectus::datasets
