// pectus trainer: the magnetometer's hard- and soft-iron calibration by an ellipsoid fit (the readings of a
// calibration wave, the scope turned every way in the hand before it goes in, lie on an ellipsoid: m = S B +
// h, |B| constant; NXP AN4246/AN4247, "Calibrating an eCompass in the presence of hard- and soft-iron
// interference"). The fit is the algebraic one: the quadric m^T A m + b^T m + c = 0 nearest the readings
// in least squares (the right singular vector of the smallest singular value), its centre the hard-iron
// offset h = -A^-1 b / 2 and the symmetric square root of A, scaled, the soft-iron correction W = S^-1
// (S taken symmetric, as it is for induced fields).
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

namespace pectus::trainer {

/// The correction of raw magnetometer readings: corrected = soft_iron_correction (raw - hard_iron_offset).
struct MagnetometerCalibration {
  Eigen::Vector3d hard_iron_offset = Eigen::Vector3d::Zero();          ///< the readings' units (uT)
  Eigen::Matrix3d soft_iron_correction = Eigen::Matrix3d::Identity();  ///< symmetric, unitless
  double field_strength = 0;  ///< |corrected|, the mean over the readings (uT)
  double rms_residual = 0;    ///< RMS of |corrected| - field_strength over the readings (uT)
  Eigen::Vector3d Apply(const Eigen::Vector3d& raw) const {
    return soft_iron_correction * (raw - hard_iron_offset);
  }
};

/// Fits the calibration to readings that span the orientations (at least 9, spread over the sphere).
/// Throws Error(kBadInput) when the readings do not determine an ellipsoid (too few, all in a plane, or a
/// quadric that is not an ellipsoid); `what` names them in the message.
MagnetometerCalibration FitMagnetometerCalibration(const std::vector<Eigen::Vector3d>& readings_uT,
                                                   const std::string& what = "magnetometer readings");

}  // namespace pectus::trainer
