// Shared by the trainer's tests and its benchmark: a thoracoscope's inertial unit on synthetic data with a
// known answer. The scope is held still at its port for the first seconds, then turned about it (yaw,
// pitch, roll as slow sums of sines, up to about 40 degrees); the unit samples its body rates and specific
// force with a MEMS unit's errors: gyro white noise 0.007 deg/s/sqrt(Hz) (a BMI160's), a turn-on bias of
// up to 0.5 deg/s per axis, a bias random walk of 0.0003 deg/s/sqrt(s); accelerometer white noise
// 150 ug/sqrt(Hz), and the scope's own small accelerations (0.05 m/s^2).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>
#include <random>
#include <vector>

namespace pectus::trainer::testing {

struct SyntheticImuOptions {
  double duration_s = 300, rate_hz = 100, still_s = 10;
  double gyro_noise_deg_s_rthz = 0.007, gyro_bias_deg_s = 0.5, gyro_bias_walk_deg_s_rts = 0.0003;
  double accel_noise_ug_rthz = 150, motion_accel_m_s2 = 0.05;
  unsigned seed = 1;
};

struct SyntheticImu {
  std::vector<double> time_s;
  std::vector<Eigen::Quaterniond> truth;  ///< R_world_sensor
  std::vector<Eigen::Vector3d> gyro_rad_s, accel_m_s2;
  std::vector<Eigen::Vector3d> true_accel_world_m_s2;  ///< the scope's own acceleration (gravity excluded)
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
    out.accel_m_s2.push_back(q.conjugate() * (a_world + Eigen::Vector3d(0, 0, kG)) +
                             accel_sigma * draw3(unit));
    bias += walk_sigma * draw3(unit);
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

/// Angle between two orientations, degrees.
inline double AngleDeg(const Eigen::Quaterniond& a, const Eigen::Quaterniond& b) {
  return Eigen::AngleAxisd(a.conjugate() * b).angle() * 180.0 / 3.14159265358979323846;
}

}  // namespace pectus::trainer::testing
