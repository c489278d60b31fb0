#include "planner_plugin/trainer/imu_orientation_filter.h"

#include <cmath>

#include "shape/core/error.h"

namespace pectus::trainer {

bool MadgwickOptions::IsValid(std::string* why) const {
  const bool ok = beta >= 0 && beta < 10;
  if (!ok && why != nullptr) *why = "Madgwick filter: beta must be in [0, 10)";
  return ok;
}

MadgwickFilter::MadgwickFilter(const MadgwickOptions& options, const Eigen::Quaterniond& initial)
    : options_(options), q_(initial.normalized()) {
  std::string why;
  if (!options.IsValid(&why)) ThrowUsage(why);
}

void MadgwickFilter::Update(const Eigen::Vector3d& gyro_rad_s, const Eigen::Vector3d& accel_m_s2,
                            double dt_s) noexcept {
  // q = (q0, q1, q2, q3) is R_world_sensor, so the world's up in the sensor frame is R^T z.
  const double q0 = q_.w(), q1 = q_.x(), q2 = q_.y(), q3 = q_.z();
  Eigen::Vector4d step = Eigen::Vector4d::Zero();
  const double a_norm = accel_m_s2.norm();
  if (a_norm > 1e-9) {
    const Eigen::Vector3d a = accel_m_s2 / a_norm;
    // Eq. 25: f = R^T z - a (the objective), and its Jacobian (eq. 26), for the world's up (0, 0, 1).
    const Eigen::Vector3d f(2 * (q1 * q3 - q0 * q2) - a.x(), 2 * (q0 * q1 + q2 * q3) - a.y(),
                            2 * (0.5 - q1 * q1 - q2 * q2) - a.z());
    Eigen::Matrix<double, 3, 4> J;
    J << -2 * q2, 2 * q3, -2 * q0, 2 * q1,  //
        2 * q1, 2 * q0, 2 * q3, 2 * q2,     //
        0, -4 * q1, -4 * q2, 0;
    step = J.transpose() * f;  // eq. 34: the gradient
    const double s = step.norm();
    if (s > 1e-12) step /= s;
  }
  const Eigen::Vector3d w = gyro_rad_s - bias_;
  // Eq. 42-43: q' = 1/2 q (x) (0, w) - beta step, integrated over dt.
  const Eigen::Quaterniond rate = q_ * Eigen::Quaterniond(0, w.x(), w.y(), w.z());
  Eigen::Vector4d dq(0.5 * rate.w(), 0.5 * rate.x(), 0.5 * rate.y(), 0.5 * rate.z());
  dq -= options_.beta * step;
  q_ = Eigen::Quaterniond(q0 + dt_s * dq(0), q1 + dt_s * dq(1), q2 + dt_s * dq(2), q3 + dt_s * dq(3));
  q_.normalize();
}

}  // namespace pectus::trainer
