// Shared by the trainer's tests and its benchmark: a thoracoscope's inertial unit on synthetic data with a
// known answer. The scope is held still at its port for the first seconds, then turned about it (yaw,
// pitch, roll as slow sums of sines, up to about 40 degrees); the unit samples its body rates and specific
// force with a MEMS unit's errors: gyro white noise 0.007 deg/s/sqrt(Hz) (a BMI160's), a turn-on bias of
// up to 0.5 deg/s per axis, a bias random walk of 0.0003 deg/s/sqrt(s) (about 18 deg/h after 5 min: three
// times a BMI160's bias stability, 6 deg/h typical, 10 at most); accelerometer white
// noise 150 ug/sqrt(Hz) (a BMI160's), and the scope's own small accelerations (0.05 m/s^2).
// The magnetometer (a BMM150, the BMI160's companion): read at 20 Hz with 0.6 uT RMS noise per axis (the
// datasheet gives 0.3 uT at its 20 Hz high-accuracy preset, 0.6 at the 10 Hz regular one); a hard-iron
// offset of up to 40 uT per axis (its uncalibrated zero-B offset) and a soft-iron distortion of up to 3 %
// (a symmetric matrix: the scope's own steel), both unknown to the filter and calibrated from a
// calibration wave (the scope turned every way in the hand, 200 readings); the Earth's field 50 uT at
// 65 degrees inclination (about Norfolk, Virginia's, where the dissertation was written), a static
// distortion of the room of up to 5 uT (the table, the haptic device: part of the local field learned at
// the port), and a slow disturbance in the run (metal moved near the patient: 0.2 uT, periods of minutes).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>
#include <random>
#include <vector>

#include "planner_plugin/trainer/imu_orientation_filter.h"
#include "planner_plugin/trainer/magnetometer_calibration.h"

namespace pectus::trainer::testing {

struct SyntheticImuOptions {
  double duration_s = 300, rate_hz = 100, still_s = 10;
  double gyro_noise_deg_s_rthz = 0.007, gyro_bias_deg_s = 0.5, gyro_bias_walk_deg_s_rts = 0.0003;
  double accel_noise_ug_rthz = 150, motion_accel_m_s2 = 0.05;
  double mag_rate_hz = 20, mag_noise_uT = 0.6, field_uT = 50, inclination_deg = 65;
  double hard_iron_uT = 40, soft_iron = 0.03, room_distortion_uT = 5, disturbance_uT = 0.2;
  int calibration_readings = 200;
  unsigned seed = 1;
};

struct SyntheticImu {
  std::vector<double> time_s;
  std::vector<Eigen::Quaterniond> truth;  ///< R_world_sensor
  std::vector<Eigen::Vector3d> gyro_rad_s, accel_m_s2;
  std::vector<Eigen::Vector3d> true_accel_world_m_s2;  ///< the scope's own acceleration (gravity excluded)
  std::vector<Eigen::Vector3d> mag_uT;  ///< raw magnetometer readings (hard and soft iron included)
  std::vector<char> has_mag;            ///< 1 where the sample carries a magnetometer reading
  std::vector<Eigen::Vector3d> calibration_mag_uT;  ///< the calibration wave's raw readings
  Eigen::Vector3d hard_iron_uT = Eigen::Vector3d::Zero();
  Eigen::Matrix3d soft_iron = Eigen::Matrix3d::Identity();
  Eigen::Vector3d final_gyro_bias_rad_s = Eigen::Vector3d::Zero();  ///< the bias at the last sample
};

inline Eigen::Quaterniond SyntheticOrientation(double t, double still_s) {
  const double s = std::max(0.0, t - still_s);
  const double ramp = std::min(1.0, s / 5.0);  // eases in over 5 s
  const double ramp2 = ramp * ramp * (3 - 2 * ramp);
  constexpr double kTwoPi = 2 * 3.14159265358979323846;
  const double yaw = ramp2 * (0.45 * std::sin(kTwoPi * 0.05 * s) + 0.2 * std::sin(kTwoPi * 0.17 * s));
  const double pitch = ramp2 * (0.35 * std::sin(kTwoPi * 0.11 * s) + 0.1 * std::sin(kTwoPi * 0.31 * s));
  const double roll = ramp2 * (0.3 * std::sin(kTwoPi * 0.07 * s + 1.0));
  return Eigen::Quaterniond(Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) *
                            Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
                            Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()));
}

inline SyntheticImu MakeSyntheticImu(const SyntheticImuOptions& o = {}) {
  constexpr double kDeg = 3.14159265358979323846 / 180.0, kG = 9.80665;
  std::mt19937_64 rng(o.seed);
  std::normal_distribution<double> unit(0.0, 1.0);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  const double dt = 1.0 / o.rate_hz;
  const double gyro_sigma = o.gyro_noise_deg_s_rthz * kDeg * std::sqrt(0.5 * o.rate_hz);
  const double accel_sigma = o.accel_noise_ug_rthz * 1e-6 * kG * std::sqrt(0.5 * o.rate_hz);
  const double walk_sigma = o.gyro_bias_walk_deg_s_rts * kDeg * std::sqrt(dt);
  // Draws in named order: a constructor's arguments are evaluated in an unspecified order (GCC and clang
  // differ), which would give each compiler other data.
  auto draw3 = [&](auto& distribution) {
    const double x = distribution(rng);
    const double y = distribution(rng);
    const double z = distribution(rng);
    return Eigen::Vector3d(x, y, z);
  };
  Eigen::Vector3d bias = draw3(uniform);
  bias *= o.gyro_bias_deg_s * kDeg;
  SyntheticImu out;
  const auto n = static_cast<std::size_t>(o.duration_s * o.rate_hz) + 1;
  constexpr double kTwoPi = 2 * 3.14159265358979323846;
  // The magnetometer draws from its own generator and distributions (a normal distribution keeps a
  // second value), so the gyro's and accelerometer's data do not change with it.
  std::mt19937_64 mag_rng(o.seed + 1000003u);
  std::normal_distribution<double> mag_unit(0.0, 1.0);
  std::uniform_real_distribution<double> mag_uniform(-1.0, 1.0);
  auto mag_draw3 = [&](auto& distribution) {
    const double x = distribution(mag_rng);
    const double y = distribution(mag_rng);
    const double z = distribution(mag_rng);
    return Eigen::Vector3d(x, y, z);
  };
  out.hard_iron_uT = o.hard_iron_uT * mag_draw3(mag_uniform);
  const Eigen::Vector3d diagonal = mag_draw3(mag_uniform), off = mag_draw3(mag_uniform);
  out.soft_iron << 1 + o.soft_iron * diagonal.x(), o.soft_iron * off.x(), o.soft_iron * off.y(),  //
      o.soft_iron * off.x(), 1 + o.soft_iron * diagonal.y(), o.soft_iron * off.z(),               //
      o.soft_iron * off.y(), o.soft_iron * off.z(), 1 + o.soft_iron * diagonal.z();
  const double inclination = o.inclination_deg * kDeg;
  const Eigen::Vector3d room = o.room_distortion_uT * mag_draw3(mag_uniform) / std::sqrt(3.0);
  const Eigen::Vector3d earth =
      o.field_uT * Eigen::Vector3d(std::cos(inclination), 0, -std::sin(inclination)) + room;
  const Eigen::Vector3d disturbance_axis = mag_draw3(mag_unit).normalized();
  auto reading = [&](const Eigen::Quaterniond& q, const Eigen::Vector3d& field_world) {
    return Eigen::Vector3d(out.soft_iron * (q.conjugate() * field_world) + out.hard_iron_uT +
                           o.mag_noise_uT * mag_draw3(mag_unit));
  };
  for (int i = 0; i < o.calibration_readings; ++i) {  // the calibration wave: orientations all round
    Eigen::Vector4d v = mag_draw3(mag_unit).homogeneous();
    v(3) = mag_unit(mag_rng);
    out.calibration_mag_uT.push_back(reading(Eigen::Quaterniond(v(3), v(0), v(1), v(2)).normalized(), earth));
  }
  const auto mag_every =
      std::max<std::size_t>(1, static_cast<std::size_t>(std::lround(o.rate_hz / o.mag_rate_hz)));
  for (std::size_t k = 0; k < n; ++k) {
    const double t = static_cast<double>(k) * dt;
    const Eigen::Quaterniond q = SyntheticOrientation(t, o.still_s);
    // Body rate: the rotation over a short interval centred on t.
    const double h = 1e-5;
    const Eigen::Quaterniond d =
        SyntheticOrientation(t - h, o.still_s).conjugate() * SyntheticOrientation(t + h, o.still_s);
    const Eigen::AngleAxisd aa(d);
    const Eigen::Vector3d omega = aa.axis() * (aa.angle() / (2 * h));
    const double moving = t > o.still_s ? 1.0 : 0.0;
    const Eigen::Vector3d a_world = moving * o.motion_accel_m_s2 *
                                    Eigen::Vector3d(std::sin(kTwoPi * 0.3 * t), std::cos(kTwoPi * 0.23 * t),
                                                    std::sin(kTwoPi * 0.19 * t + 0.5));
    out.time_s.push_back(t);
    out.truth.push_back(q);
    out.true_accel_world_m_s2.push_back(a_world);
    out.gyro_rad_s.push_back(omega + bias + gyro_sigma * draw3(unit));
    out.final_gyro_bias_rad_s = bias;
    out.accel_m_s2.push_back(q.conjugate() * (a_world + Eigen::Vector3d(0, 0, kG)) +
                             accel_sigma * draw3(unit));
    bias += walk_sigma * draw3(unit);
    const bool has_mag = k % mag_every == 0;
    const Eigen::Vector3d disturbance =
        o.disturbance_uT * (std::sin(kTwoPi * t / 170.0) * disturbance_axis +
                            0.5 * std::sin(kTwoPi * t / 67.0 + 2.0) * Eigen::Vector3d(0, 0, 1));
    out.mag_uT.push_back(has_mag ? reading(q, earth + moving * disturbance) : Eigen::Vector3d::Zero());
    out.has_mag.push_back(has_mag ? 1 : 0);
  }
  return out;
}

/// The gyro's bias as the mean rate while the scope lies still at its port (the first `still_s` seconds).
inline Eigen::Vector3d StillBias(const SyntheticImu& imu, double still_s) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  int n = 0;
  for (std::size_t k = 0; k < imu.time_s.size() && imu.time_s[k] < still_s; ++k, ++n)
    sum += imu.gyro_rad_s[k];
  return n > 0 ? Eigen::Vector3d(sum / n) : sum;
}

/// The local field in the world frame: the mean calibrated reading while the scope lies still at its port
/// (the first `still_s` seconds), turned by its orientation there (the world frame's heading is the
/// scope's at the port).
inline Eigen::Vector3d StillField(const SyntheticImu& imu, const MagnetometerCalibration& calibration,
                                  double still_s) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (std::size_t k = 0; k < imu.time_s.size() && imu.time_s[k] < still_s; ++k)
    if (imu.has_mag[k]) sum += calibration.Apply(imu.mag_uT[k]);
  return imu.truth.front() * sum;
}

/// The filter's orientation at every sample (the first is the initial one, the truth's): the gyro's bias
/// from the still interval, then either the IMU form (gravity only) or the MARG form (the magnetometer
/// calibrated from the calibration wave, the local field from the still interval).
inline std::vector<Eigen::Quaterniond> TrackOrientation(const SyntheticImu& imu, const SyntheticImuOptions& o,
                                                        const MadgwickOptions& options,
                                                        bool use_magnetometer) {
  MadgwickFilter filter(options, imu.truth.front());
  filter.SetGyroBias(StillBias(imu, o.still_s));
  MagnetometerCalibration calibration;
  if (use_magnetometer) {
    calibration = FitMagnetometerCalibration(imu.calibration_mag_uT, "the calibration wave");
    filter.SetMagneticReference(StillField(imu, calibration, o.still_s));
  }
  std::vector<Eigen::Quaterniond> out = {filter.orientation()};
  for (std::size_t k = 1; k < imu.time_s.size(); ++k) {
    const double dt = imu.time_s[k] - imu.time_s[k - 1];
    if (use_magnetometer && imu.has_mag[k])
      filter.Update(imu.gyro_rad_s[k], imu.accel_m_s2[k], calibration.Apply(imu.mag_uT[k]), dt);
    else
      filter.Update(imu.gyro_rad_s[k], imu.accel_m_s2[k], dt);
    out.push_back(filter.orientation());
  }
  return out;
}

/// Angle between two orientations, degrees.
inline double AngleDeg(const Eigen::Quaterniond& a, const Eigen::Quaterniond& b) {
  return Eigen::AngleAxisd(a.conjugate() * b).angle() * 180.0 / 3.14159265358979323846;
}

}  // namespace pectus::trainer::testing
