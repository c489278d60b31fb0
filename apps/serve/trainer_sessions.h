// pectus serve: the Nuss trainer's sessions behind the planner page (issue 16). Each session is a patient's
// trainer in the plugin (TrainerClient) whose 1 kHz servo thread reads a PointerDevice: the page's pointer
// (or keyboard, or gamepad) sets the introducer's target over HTTP, the device glides to it between
// messages so the haptic loop sees a continuous hand, and the shaft's axis trails the tip along its path.
// Answers are JSON (docs/trainer.md, "The trainer in the planner page"); the record of a finished session
// is kept for download.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <chrono>
#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <string>

#include "planner_plugin/api/planner_api.h"
#include "planner_plugin/host/planner_client.h"
#include "planner_plugin/host/trainer_client.h"

namespace pectus::serve {

/// A device moved by messages (the page's pointer, an outside driver): the state the servo thread reads
/// glides linearly from where it was to each new target over the time since the message before (5-100
/// ms), and the tool's axis points from an anchor trailing 20 mm behind the tip to the tip.
class PointerDevice {
 public:
  using Clock = std::chrono::steady_clock;
  /// At `start_mm` with the shaft pointing along `axis` (unit).
  PointerDevice(const Eigen::Vector3d& start_mm, const Eigen::Vector3d& axis);
  /// A new target (any thread).
  void MoveTo(const Eigen::Vector3d& target_mm, std::uint32_t buttons);
  /// A device's own state (a driver's, at its servo rate): taken as it is, no gliding, its orientation.
  void Set(const Eigen::Vector3d& position_mm, const Eigen::Quaterniond& orientation, std::uint32_t buttons);
  /// The callbacks for the plugin's servo thread (never blocking: a reading that finds the target being
  /// moved gives the last one again).
  PectusPlannerDevice Callbacks();
  /// Where the device is, at `now`.
  PectusPlannerDeviceState StateAt(Clock::time_point now);

 private:
  static void Read(void* user, double time_s, PectusPlannerDeviceState* out);
  static void SetForce(void*, const double*, const double*) {}
  std::mutex mutex_;
  Eigen::Vector3d from_, to_, anchor_;
  Clock::time_point moved_at_, previous_move_;
  double glide_s_ = 0.03;
  std::uint32_t buttons_ = 0;
  bool has_orientation_ = false;  // Set() gave one
  Eigen::Quaterniond orientation_ = Eigen::Quaterniond::Identity();
  PectusPlannerDeviceState last_{};  // the servo thread's own
};

/// The trainer sessions of one server (at most `max_sessions` at once; the oldest is finished for a new one;
/// one idle for `idle_s` is finished at the next request).
class TrainerSessions {
 public:
  TrainerSessions(const planner::PlannerPlugin& plugin, std::filesystem::path work_dir, int max_sessions = 2,
                  double idle_s = 300);
  ~TrainerSessions();
  /// A session of `patient` with `introducer` on `planner` (whose lock the caller holds while this runs;
  /// the trainer copies what it needs). Returns the scene: tunnel, ports, meshes' sizes, the device's start.
  nlohmann::json Start(const planner::PlannerClient& planner, const std::string& patient,
                       const std::string& introducer);
  /// The scene's meshes of a session, binary: pericardium, right lung, left lung (float32 vertices, then
  /// uint32 faces, each).
  std::string Meshes(const std::string& session);
  /// Moves the device (position in mm, buttons) and answers the latest tick, the scope's view and the
  /// score so far (recomputed at most five times a second).
  nlohmann::json Device(const std::string& session, const Eigen::Vector3d& position_mm,
                        std::uint32_t buttons);
  /// A driver's device state (device_protocol.h): the session's device set to it; the latest tick into
  /// `tick`. Returns a DeviceProtocolStatus (0 ok, 1 no such session, 3 finished). Quick: no JSON.
  std::uint32_t DriverMove(const std::string& session, const Eigen::Vector3d& position_mm,
                           const Eigen::Quaterniond& orientation, std::uint32_t buttons,
                           PectusPlannerTrainerTick* tick);
  /// Stops the session's servo loop and answers its report: scores, the loop's timing, the replay check.
  nlohmann::json Finish(const std::string& session);
  /// The record of a session (text, docs/trainer.md "Session records").
  std::string Record(const std::string& session);

 private:
  struct Session;
  std::shared_ptr<Session> Find(const std::string& id);
  void Expire();
  const planner::PlannerPlugin& plugin_;
  std::filesystem::path work_dir_;
  int max_sessions_;
  double idle_s_;
  std::mutex mutex_;
  std::map<std::string, std::shared_ptr<Session>> sessions_;
  std::uint64_t next_ = 1;
};

/// A session's score as the page and the report show it.
nlohmann::json TrainerScoreJson(const PectusPlannerTrainerScore& score, const PectusPlannerTunnel& tunnel);

}  // namespace pectus::serve
