// pectus planner plugin: one patient's trainer behind the C interface (planner_api.h, version 5): the
// trainer's scene made from the planner's fitted ribcage, a session ticked either by the host in its own
// thread (a device state given per tick) or by the plugin's 1 kHz servo thread reading the host's device
// (PectusPlannerDevice), the latest tick published to other threads without ever blocking the servo
// thread, and the session's scores, record and replay; the thoracoscope's view at its port.
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>

#include "planner_plugin/api/planner_api.h"
#include "planner_plugin/ribcage/patient_ribcage.h"
#include "planner_plugin/trainer/haptic_device.h"
#include "planner_plugin/trainer/servo_loop.h"
#include "planner_plugin/trainer/session_score.h"
#include "planner_plugin/trainer/thoracoscope.h"
#include "planner_plugin/trainer/trainer_scene.h"
#include "planner_plugin/trainer/trainer_session.h"

namespace pectus::planner {

/// The host's device: its callbacks (the servo thread's), or a state the host hands over tick by tick.
class HostDevice final : public trainer::HapticDevice {
 public:
  void UseCallbacks(const PectusPlannerDevice& device) { callbacks_ = device; }
  void UseHeld() { callbacks_ = {}; }
  void Hold(const trainer::DeviceState& state) { held_ = state; }
  trainer::DeviceInfo Info() const override { return {"host", 8.5, 3.5, false}; }
  trainer::DeviceState Read(double time_s) noexcept override;
  void SetForceAndTorque(const Eigen::Vector3d& force_n, const Eigen::Vector3d& torque_nmm) noexcept override;
  /// What the last Read() gave.
  const trainer::DeviceState& last() const { return last_; }

 private:
  PectusPlannerDevice callbacks_{};
  trainer::DeviceState held_, last_;
};

/// The object behind PectusPlannerTrainer*.
class PlannerTrainer {
 public:
  /// Builds the scene of `ribcage` and an empty session. Throws pectus::Error (kBadInput for an unknown
  /// introducer, kUsage for capacity < 0).
  PlannerTrainer(const PatientRibcage& ribcage, const std::string& introducer, std::int64_t capacity_ticks);
  ~PlannerTrainer();

  const trainer::TrainerScene& scene() const { return scene_; }
  /// The thoracoscope's port: the right space below the planned entry (above it if there is none).
  const Eigen::Vector3d& scope_port() const { return scope_port_; }

  /// A new, empty session. Throws Error(kUsage) while the servo thread runs.
  void Reset();
  /// One tick in the caller's thread; false (nothing done) with `why` while the servo thread runs, for a
  /// non-finite state or a time before the last tick's.
  bool Tick(const PectusPlannerDeviceState& state, PectusPlannerTrainerTick* out, const char** why) noexcept;
  /// A new session on the servo thread at `rate_hz`, reading `device`. Throws Error(kUsage) if running.
  void Start(const PectusPlannerDevice& device, double rate_hz);
  /// Stops the servo thread; its statistics (zero if it was not running).
  trainer::ServoLoopStatistics Stop();
  bool running() const { return loop_ && loop_->running(); }
  /// The latest tick; false before the first.
  bool Latest(PectusPlannerTrainerTick* out) const;
  /// The ticks and events recorded so far (a copy; any thread).
  trainer::SessionRecord RecordSoFar() const;
  /// Their scores. Throws Error(kUsage) for fewer than two ticks.
  trainer::SessionScore Score() const;

  /// The scope's view: orientation given, or aimed at `target` (docs: planner_api.h trainer_scope_view).
  PectusPlannerScopeView ScopeView(const Eigen::Quaterniond* orientation, const Eigen::Vector3d& target,
                                   double insertion_mm) const;

 private:
  void TickAndPublish(double time_s) noexcept;

  trainer::TrainerScene scene_;
  const trainer::Introducer* introducer_;
  std::int64_t capacity_;
  Eigen::Vector3d scope_port_;
  trainer::ScopeCamera camera_;
  HostDevice device_;
  std::unique_ptr<trainer::TrainerSession> session_;
  std::unique_ptr<trainer::ServoLoop> loop_;
  // What other threads may read while the servo thread ticks: the record's first `committed_samples_`
  // samples and `committed_events_` events (never written again once committed), and the latest tick
  // (the servo thread skips publishing it in the rare tick a reader holds the mutex: it never waits).
  std::atomic<std::int64_t> committed_samples_{0}, committed_events_{0};
  mutable std::mutex latest_mutex_;
  PectusPlannerTrainerTick latest_{};
  bool has_latest_ = false;
  double last_time_s_ = 0;
};

}  // namespace pectus::planner
