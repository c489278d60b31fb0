// pectus trainer: the thoracoscope's orientation from an inertial unit by Madgwick's gradient-descent
// filter on quaternions (Madgwick, Harrison & Vaidyanathan 2011, "Estimation of IMU and MARG orientation
// using a gradient descent algorithm"): gyro rates integrated, corrected by a gradient step that turns the
// measured specific force towards the world's up (IMU form, eqs. 25-26) and, with a magnetometer, the
// measured field towards the local field's direction (MARG form, eqs. 29-34): gravity holds the tilt, the
// field the heading. The gyro's bias is taken from a still interval at the port (SetGyroBias) and then
// followed on-line (the gyro bias drift compensation, eqs. 47-48). Orientation only: position is not
// integrated from the accelerations (docs/trainer.md: double integration drifts metres in minutes); the
// scope's tip follows from the port (thoracoscope.h).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <string>

namespace pectus::trainer {

struct MadgwickOptions {
  /// Gain of the accelerometer's (and magnetometer's) correction, rad/s: sqrt(3/4) times the gyro's error
  /// it should absorb. Default 0.003 (measured best of 0.003-0.1 on the synthetic scope's data:
  /// docs/benchmarks.md).
  double beta = 0.003;
  /// Gain of the on-line gyro bias estimate (Madgwick's zeta, eqs. 47-48), 1/s; 0 keeps the bias given by
  /// SetGyroBias. The bias integrates zeta times the rate error w_e = 2 q* (x) grad f, the gradient taken
  /// as it is, not normalised: proportional to the error, as Mahony's integral term is (the normalised
  /// gradient of eq. 47 points wherever the sensors' noise does once the filter has converged, and its
  /// integral wandered: 0.60-0.66 deg RMS against 0.31 here, docs/benchmarks.md). Default 0.0015: on the
  /// synthetic scope's data with a magnetometer, 0.001-0.003 gave 0.30-0.35 deg RMS on the worst of 10
  /// seeds, 0.0001 0.46 and 0.01 0.75.
  double zeta = 0.0015;
  bool IsValid(std::string* why) const;
};

/// The filter. Frames: the world's z axis is up (gravity is -z); orientation() is R_world_sensor.
class MadgwickFilter {
 public:
  explicit MadgwickFilter(const MadgwickOptions& options = {},
                          const Eigen::Quaterniond& initial = Eigen::Quaterniond::Identity());
  /// One sample (IMU form): angular rate in the sensor frame (rad/s), specific force in the sensor frame
  /// (m/s^2; at rest it points up, +9.81 along the world's z), the sample interval dt_s. No allocation;
  /// never throws.
  void Update(const Eigen::Vector3d& gyro_rad_s, const Eigen::Vector3d& accel_m_s2, double dt_s) noexcept;
  /// One sample with a magnetometer reading (MARG form): `mag` in the sensor frame, calibrated (hard and
  /// soft iron removed: magnetometer_calibration.h), any unit. Falls back to the IMU form until
  /// SetMagneticReference has been called, or when the reading is zero.
  void Update(const Eigen::Vector3d& gyro_rad_s, const Eigen::Vector3d& accel_m_s2,
              const Eigen::Vector3d& mag, double dt_s) noexcept;
  /// The local magnetic field in the world frame (any unit; only its direction is used), e.g. the mean
  /// calibrated reading over a still interval turned by the orientation then. The local field, not the
  /// Earth's model: the room's static distortion is part of it.
  void SetMagneticReference(const Eigen::Vector3d& field_world);
  /// The gyro's bias, e.g. the mean rate over a still interval (rad/s), subtracted from every sample.
  void SetGyroBias(const Eigen::Vector3d& bias_rad_s) { bias_ = bias_rad_s; }
  const Eigen::Vector3d& gyro_bias() const { return bias_; }
  Eigen::Quaterniond orientation() const { return q_; }

 private:
  void Step(const Eigen::Vector3d& gyro_rad_s, const Eigen::Vector4d& gradient, double dt_s) noexcept;
  MadgwickOptions options_;
  Eigen::Quaterniond q_;
  Eigen::Vector3d bias_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d field_world_ = Eigen::Vector3d::Zero();  ///< unit, or zero when not set
};

}  // namespace pectus::trainer
