// pectus datasets: the parameters of one synthetic chest (docs/datasets.md, "The chest model").
//
// Frame (mm), the "chest frame" of every generated file: x to the subject's left, y up (superior, toward the
// head), z anterior (out of the chest); right-handed. Origin on the midline, at the height of the sternal
// notch, in the coronal plane of the mid-axillary lines. The scanned (anterior) surface therefore faces +z,
// and render::View::Front() shows it face on with the subject's left on the picture's right.
#pragma once

#include <Eigen/Core>
#include <nlohmann/json.hpp>
#include <string>

#include "shape/core/geometry.h"

namespace pectus::datasets {

/// The two morphologies of pectus excavatum.
enum class PectusType {
  kSaucer,  ///< broad, shallow-walled (Gaussian profile)
  kCup,     ///< localised, steep-walled, flat-bottomed (super-Gaussian profile, order 4)
};

/// "saucer" / "cup"; throws Error(kUsage) for anything else.
PectusType ParsePectusType(const std::string& text);
std::string ToString(PectusType type);

/// A pectus excavatum depression of the chest wall (the skin follows it). Zero depth means none.
struct PectusParameters {
  double depth_mm = 0.0;  ///< deepest inward displacement of the chest wall, mm, [0, 60]
  PectusType type = PectusType::kSaucer;
  double centre_x_mm = 0.0;  ///< lateral offset of the centre from the midline, mm (+: subject's left)
  double centre_y_mm = 0.0;  ///< height of the centre above the reference level (30 % of the sternum above
                             ///< the xiphoid), mm
  double width_mm = 0.0;     ///< lateral radius (standard deviation of the profile), mm; 0: 0.12 W (saucer),
                             ///< 0.075 W (cup)
  double height_mm = 0.0;    ///< vertical radius, mm; 0: 0.22 L (saucer), 0.10 L (cup)
  double asymmetry = 0.0;    ///< [-0.6, 0.6]: the left half is (1 + a) times as wide, the right half (1 - a)
  /// Sternal torsion, [-45, 45] degrees: the floor of the depression turns about the sternal axis; + sinks
  /// the subject's right side (the deepest point moves right).
  double torsion_deg = 0.0;
  double axis_deg = 0.0;  ///< rotation of the depression's lateral axis in the coronal plane, degrees

  bool IsValid(std::string* why) const;
};

/// Every parameter of one chest. The surface is affine in every field except `pectus`, `growth` and
/// `T_scan_subject`, so a population of these (datasets/chest_population.h) has an exactly known mean and
/// covariance.
struct ChestParameters {
  // Chest wall (outer surface of the ribcage and sternum).
  double width_mm = 270.0;  ///< W: chest-wall width at the reference level, mid-axillary to mid-axillary
  double depth_mm = 190.0;  ///< D: antero-posterior chest-wall depth at the reference level; the back
                            ///< (not modelled, not scanned) lies in the plane z = -D / 2
  double sternal_length_mm = 170.0;   ///< L: height from the sternal notch down to the xiphoid
  double costal_recession_mm = 10.0;  ///< how far the abdomen below the costal margins lies behind the chest
  double costal_ridge_mm = 3.0;       ///< prominence of the costal margins
  // Soft tissue laid over the wall along the reference normal.
  double soft_tissue_mm = 7.0;     ///< base thickness
  double pectoral_mm = 9.0;        ///< pectoralis major bulges
  double breast_mm = 5.0;          ///< breast bulges
  double sternal_groove_mm = 4.0;  ///< thinning over the sternum between the pectorals
  double concavity_mm = 2.5;       ///< natural mild mid-chest concavity
  double notch_mm = 8.0;           ///< depth of the suprasternal (jugular) notch
  double clavicle_mm = 3.0;        ///< prominence of the medial clavicles
  /// Subject-specific detail: kDetailCoefficients coefficients (mm) of a bicubic B-spline added to the soft
  /// tissue thickness; empty means zero.
  Eigen::VectorXd detail_mm;

  PectusParameters pectus;  ///< none by default
  /// Per-axis scale about the origin (the sternal notch): (lateral x, vertical y, antero-posterior z); 1 =
  /// none.
  Eigen::Vector3d growth = Eigen::Vector3d::Ones();
  Rigid3 T_scan_subject = Rigid3::Identity();  ///< pose of the subject in the scan (world) frame

  bool IsValid(std::string* why) const;
};

/// Size of the detail B-spline: kDetailU coefficients across, kDetailV up.
inline constexpr int kDetailU = 12;
inline constexpr int kDetailV = 10;
inline constexpr int kDetailCoefficients = kDetailU * kDetailV;

/// Number of scalar fields in the linear part of ChestParameters (12 named ones + the detail).
inline constexpr int kLinearParameterCount = 12 + kDetailCoefficients;

/// The affine part as a vector: [W, D, L, recession, ridge, tissue, pectoral, breast, groove, concavity,
/// notch, clavicle, detail...] (kLinearParameterCount entries, mm).
Eigen::VectorXd LinearPart(const ChestParameters& p);
/// Sets the affine part from such a vector (other fields untouched).
void SetLinearPart(const Eigen::VectorXd& x, ChestParameters* p);
/// Names of the entries of LinearPart ("width_mm", ..., "detail_000", ...).
std::string LinearParameterName(int index);

/// Growth of the same subject over some years: the chest is scaled about the origin (the sternal notch)
/// by these factors per axis.
struct GrowthOptions {
  double years = 2.0;
  double width_per_year = 0.03;      ///< relative lateral growth per year
  double depth_per_year = 0.025;     ///< relative antero-posterior growth per year
  double height_per_year = 0.05;     ///< relative vertical growth per year
  double pectus_depth_factor = 1.0;  ///< the depression's depth is multiplied by this (1: unchanged)
};

/// The same subject after growth (scale multiplied into `growth`; pectus depth scaled).
ChestParameters Grow(const ChestParameters& p, const GrowthOptions& options);

/// JSON with every field (doubles round-trip exactly).
nlohmann::json ToJson(const ChestParameters& p);
/// Reads what ToJson wrote; throws Error(kBadInput) naming `what` for a missing or wrong field.
ChestParameters ChestParametersFromJson(const nlohmann::json& j, const std::string& what);

}  // namespace pectus::datasets
