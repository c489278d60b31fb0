#include "planner_plugin/trainer/imu_orientation_filter.h"

#include <cmath>

#include "shape/core/error.h"

namespace pectus::trainer {
namespace {

// Eq. 25-26 for a world direction d: the objective f = R^T d - s (d seen from the sensor, minus the
// measured direction s, both unit) and its Jacobian in (q0, q1, q2, q3) = (w, x, y, z); returns J^T f,
// the objective's gradient (eq. 34; eq. 33 stacks the two fields' terms, which sums their gradients).
Eigen::Vector4d Gradient(const Eigen::Quaterniond& q, const Eigen::Vector3d& d, const Eigen::Vector3d& s) {
  const double q0 = q.w(), q1 = q.x(), q2 = q.y(), q3 = q.z();
  const double dx = d.x(), dy = d.y(), dz = d.z();
  const Eigen::Vector3d f(2 * dx * (0.5 - q2 * q2 - q3 * q3) + 2 * dy * (q0 * q3 + q1 * q2) +
                              2 * dz * (q1 * q3 - q0 * q2) - s.x(),
                          2 * dx * (q1 * q2 - q0 * q3) + 2 * dy * (0.5 - q1 * q1 - q3 * q3) +
                              2 * dz * (q0 * q1 + q2 * q3) - s.y(),
                          2 * dx * (q0 * q2 + q1 * q3) + 2 * dy * (q2 * q3 - q0 * q1) +
                              2 * dz * (0.5 - q1 * q1 - q2 * q2) - s.z());
  Eigen::Matrix<double, 3, 4> J;
  J << 2 * dy * q3 - 2 * dz * q2, 2 * dy * q2 + 2 * dz * q3, -4 * dx * q2 + 2 * dy * q1 - 2 * dz * q0,
      -4 * dx * q3 + 2 * dy * q0 + 2 * dz * q1,  //
      -2 * dx * q3 + 2 * dz * q1, 2 * dx * q2 - 4 * dy * q1 + 2 * dz * q0, 2 * dx * q1 + 2 * dz * q3,
      -2 * dx * q0 - 4 * dy * q3 + 2 * dz * q2,  //
      2 * dx * q2 - 2 * dy * q1, 2 * dx * q3 - 2 * dy * q0 - 4 * dz * q1,
      2 * dx * q0 + 2 * dy * q3 - 4 * dz * q2, 2 * dx * q1 + 2 * dy * q2;
  return J.transpose() * f;
}

}  // namespace

bool MadgwickOptions::IsValid(std::string* why) const {
  const bool ok = beta >= 0 && beta < 10 && zeta >= 0 && zeta < 10;
  if (!ok && why != nullptr) *why = "Madgwick filter: beta and zeta must be in [0, 10)";
  return ok;
}

MadgwickFilter::MadgwickFilter(const MadgwickOptions& options, const Eigen::Quaterniond& initial)
    : options_(options), q_(initial.normalized()) {
  std::string why;
  if (!options.IsValid(&why)) ThrowUsage(why);
}

void MadgwickFilter::SetMagneticReference(const Eigen::Vector3d& field_world) {
  const double n = field_world.norm();
  if (!(n > 0) || !std::isfinite(n))
    ThrowUsage("Madgwick filter: the magnetic reference must be a non-zero field");
  field_world_ = field_world / n;
}

void MadgwickFilter::Update(const Eigen::Vector3d& gyro_rad_s, const Eigen::Vector3d& accel_m_s2,
                            double dt_s) noexcept {
  Eigen::Vector4d gradient = Eigen::Vector4d::Zero();
  const double a_norm = accel_m_s2.norm();
  if (a_norm > 1e-9) gradient = Gradient(q_, Eigen::Vector3d::UnitZ(), accel_m_s2 / a_norm);
  Step(gyro_rad_s, gradient, dt_s);
}

void MadgwickFilter::Update(const Eigen::Vector3d& gyro_rad_s, const Eigen::Vector3d& accel_m_s2,
                            const Eigen::Vector3d& mag, double dt_s) noexcept {
  const double m_norm = mag.norm();
  if (field_world_.isZero() || !(m_norm > 1e-12)) return Update(gyro_rad_s, accel_m_s2, dt_s);
  Eigen::Vector4d gradient = Gradient(q_, field_world_, mag / m_norm);
  const double a_norm = accel_m_s2.norm();
  if (a_norm > 1e-9) gradient += Gradient(q_, Eigen::Vector3d::UnitZ(), accel_m_s2 / a_norm);
  Step(gyro_rad_s, gradient, dt_s);
}

void MadgwickFilter::Step(const Eigen::Vector3d& gyro_rad_s, const Eigen::Vector4d& gradient,
                          double dt_s) noexcept {
  Eigen::Vector4d step = gradient;
  const double s = step.norm();
  if (s > 1e-12) step /= s;
  // Eq. 47-48 on the gradient as it is (not normalised): the rate error w_e = 2 q* (x) grad f, integrated
  // into the bias with the gain zeta.
  if (options_.zeta > 0) {
    const Eigen::Quaterniond e =
        q_.conjugate() * Eigen::Quaterniond(gradient(0), gradient(1), gradient(2), gradient(3));
    bias_ += options_.zeta * dt_s * 2.0 * e.vec();
  }
  const Eigen::Vector3d w = gyro_rad_s - bias_;
  // Eq. 42-43: q' = 1/2 q (x) (0, w) - beta step, integrated over dt.
  const Eigen::Quaterniond rate = q_ * Eigen::Quaterniond(0, w.x(), w.y(), w.z());
  Eigen::Vector4d dq(0.5 * rate.w(), 0.5 * rate.x(), 0.5 * rate.y(), 0.5 * rate.z());
  dq -= options_.beta * step;
  q_ = Eigen::Quaterniond(q_.w() + dt_s * dq(0), q_.x() + dt_s * dq(1), q_.y() + dt_s * dq(2),
                          q_.z() + dt_s * dq(3));
  q_.normalize();
}

}  // namespace pectus::trainer
