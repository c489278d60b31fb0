// pectus trainer: the thoracoscope's orientation from an inertial unit (gyroscope + accelerometer) by
// Madgwick's gradient-descent filter on quaternions (Madgwick, Harrison & Vaidyanathan 2011, "Estimation
// of IMU and MARG orientation using a gradient descent algorithm"; its IMU form, eqs. 25-33), the gyro's
// bias taken from a still interval at the port (SetGyroBias). Orientation only: position is not integrated
// from the accelerations (docs/trainer.md: double integration drifts metres in minutes); the scope's tip
// follows from the port (thoracoscope.h).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <string>

namespace pectus::trainer {

struct MadgwickOptions {
  /// Gain of the accelerometer's correction, rad/s: sqrt(3/4) times the gyro's error it should absorb.
  /// Default 0.003 (measured best of 0.003-0.1 on the synthetic scope's data: docs/benchmarks.md).
  double beta = 0.003;
  bool IsValid(std::string* why) const;
};

/// The filter. Frames: the world's z axis is up (gravity is -z); orientation() is R_world_sensor.
class MadgwickFilter {
 public:
  explicit MadgwickFilter(const MadgwickOptions& options = {},
                          const Eigen::Quaterniond& initial = Eigen::Quaterniond::Identity());
  /// One sample: angular rate in the sensor frame (rad/s), specific force in the sensor frame (m/s^2; at
  /// rest it points up, +9.81 along the world's z), the sample interval dt_s. No allocation; never throws.
  void Update(const Eigen::Vector3d& gyro_rad_s, const Eigen::Vector3d& accel_m_s2, double dt_s) noexcept;
  /// The gyro's bias, e.g. the mean rate over a still interval (rad/s), subtracted from every sample.
  void SetGyroBias(const Eigen::Vector3d& bias_rad_s) { bias_ = bias_rad_s; }
  const Eigen::Vector3d& gyro_bias() const { return bias_; }
  Eigen::Quaterniond orientation() const { return q_; }

 private:
  MadgwickOptions options_;
  Eigen::Quaterniond q_;
  Eigen::Vector3d bias_ = Eigen::Vector3d::Zero();
};

}  // namespace pectus::trainer
