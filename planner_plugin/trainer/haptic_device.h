// pectus trainer: the haptic device, in the style of CHAI3D's generic device (cGenericHapticDevice):
// position, orientation, velocity, buttons read each servo tick, a force (and torque) sent back. Backends
// here: a scripted device replaying a trajectory file, and a simulated hand (a mass-spring-damper
// following a scripted target, closed loop, in simulated time, so tests are exact). Units: mm, s, N, N mm.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace pectus::trainer {

/// One reading of a device.
struct DeviceState {
  double time_s = 0;
  Eigen::Vector3d position_mm = Eigen::Vector3d::Zero();  ///< the tool's tip, scene frame
  /// The tool's orientation: its axis, from the handle to the tip, is orientation * (0, 0, 1).
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();
  Eigen::Vector3d velocity_mm_s = Eigen::Vector3d::Zero();
  std::uint32_t buttons = 0;  ///< bit i: button i pressed
};

/// What a device can do (CHAI3D's cHapticDeviceInfo, in part).
struct DeviceInfo {
  std::string model;
  double max_force_n = 8.5;             ///< Phantom Premium 1.5/6DOF (dissertation §4.4)
  double max_stiffness_n_per_mm = 3.5;  ///< the stiffest wall it renders stably
  bool has_torque = false;
};

/// A haptic device. The servo thread calls Read() then SetForceAndTorque() once per tick; neither
/// allocates, locks or throws.
class HapticDevice {
 public:
  virtual ~HapticDevice() = default;
  virtual DeviceInfo Info() const = 0;
  /// The device's state at time `time_s` (s since the session's start; never decreasing).
  virtual DeviceState Read(double time_s) noexcept = 0;
  /// The force (N) and torque (N mm) to render until the next tick.
  virtual void SetForceAndTorque(const Eigen::Vector3d& force_n,
                                 const Eigen::Vector3d& torque_nmm) noexcept = 0;
};

/// A timed sequence of device states: the trajectory file's content.
struct Trajectory {
  std::vector<DeviceState> samples;  ///< time ascending
  /// The state at `time_s`: linear in position and velocity, spherical in orientation, buttons of the
  /// sample at or before; held before the first and after the last sample. A sample's own time gives
  /// that sample bit for bit.
  DeviceState At(double time_s) const noexcept;
  double duration_s() const { return samples.empty() ? 0 : samples.back().time_s - samples.front().time_s; }
};

/// Reads a trajectory file (docs/trainer.md, "Trajectory files"): text, one sample a line,
/// `t_s x_mm y_mm z_mm qw qx qy qz buttons`, `#` comments and blank lines skipped, times increasing.
/// Velocities are the central differences of the positions. Throws Error(kBadInput) naming the file and
/// line.
Trajectory ReadTrajectory(const std::filesystem::path& path);
/// The same from text (`source` names it in messages).
Trajectory ParseTrajectory(const std::string& text, const std::string& source);
/// The file's text of `trajectory`: every number with 17 significant digits, so it reads back bit for bit.
std::string FormatTrajectory(const Trajectory& trajectory);
/// Writes FormatTrajectory() atomically.
void WriteTrajectory(const std::filesystem::path& path, const Trajectory& trajectory);

/// Replays a trajectory; the forces sent are kept (last_force_n) but move nothing.
class ScriptedDevice final : public HapticDevice {
 public:
  explicit ScriptedDevice(Trajectory trajectory) : trajectory_(std::move(trajectory)) {}
  DeviceInfo Info() const override { return {"scripted", 8.5, 3.5, false}; }
  DeviceState Read(double time_s) noexcept override { return trajectory_.At(time_s); }
  void SetForceAndTorque(const Eigen::Vector3d& force_n, const Eigen::Vector3d&) noexcept override {
    last_force_n_ = force_n;
  }
  const Eigen::Vector3d& last_force_n() const { return last_force_n_; }
  const Trajectory& trajectory() const { return trajectory_; }

 private:
  Trajectory trajectory_;
  Eigen::Vector3d last_force_n_ = Eigen::Vector3d::Zero();
};

/// The hand that holds the tool, as a mass pulled towards a scripted target by a spring and a damper:
/// m a = k (target - x) - b v + F, with F the force the device renders. Integrated by semi-implicit Euler
/// in fixed steps of `step_s` (Read() advances to the asked time in whole steps), so a run is exact and
/// repeatable. Defaults: a hand and stylus of 0.1 kg, a grip of 0.3 N/mm, damping 5 N s/m (a relaxed
/// grip), steps of 1 ms (the servo period).
struct SimulatedHandOptions {
  double mass_kg = 0.1;
  double grip_n_per_mm = 0.3;
  double damping_n_s_per_mm = 0.005;
  double step_s = 0.001;
  bool IsValid(std::string* why) const;
};
class SimulatedHand final : public HapticDevice {
 public:
  /// Throws Error(kUsage) for invalid options or an empty target.
  SimulatedHand(Trajectory target, const SimulatedHandOptions& options = {});
  DeviceInfo Info() const override { return {"simulated hand", 8.5, 3.5, false}; }
  DeviceState Read(double time_s) noexcept override;
  void SetForceAndTorque(const Eigen::Vector3d& force_n, const Eigen::Vector3d&) noexcept override {
    force_n_ = force_n;
  }
  const Trajectory& target() const { return target_; }

 private:
  Trajectory target_;
  SimulatedHandOptions options_;
  double time_s_ = 0;
  Eigen::Vector3d x_mm_, v_mm_s_;
  Eigen::Vector3d force_n_ = Eigen::Vector3d::Zero();
};

}  // namespace pectus::trainer
