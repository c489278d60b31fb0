// pectus trainer: a training session: each servo tick reads the device, moves the proxy, sends the force
// back and records the tick (trajectory, forces, contact events) into buffers sized up front. A session's
// record is written atomically as text that reads back bit for bit, and replays (the recorded device
// states fed back through a scripted device) to the same proxies, forces and scores.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "planner_plugin/trainer/god_object.h"
#include "planner_plugin/trainer/haptic_device.h"
#include "planner_plugin/trainer/trainer_scene.h"

namespace pectus::trainer {

/// One servo tick.
struct SessionSample {
  double time_s = 0;
  Eigen::Vector3d device_mm = Eigen::Vector3d::Zero();  ///< the device's tip (the proxy's goal)
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();
  Eigen::Vector3d proxy_mm = Eigen::Vector3d::Zero();  ///< the introducer's tip as drawn
  Eigen::Vector3d force_n = Eigen::Vector3d::Zero();   ///< sent to the device
  std::uint32_t organs_touched = 0;                    ///< bit Organ
  double pericardium_force_n = 0;
};

/// A contact with an organ beginning or ending.
struct SessionEvent {
  double time_s = 0;
  int organ = kBone;
  bool begins = true;
};

/// Everything a session leaves behind.
struct SessionRecord {
  std::string patient;
  std::string introducer;  ///< IntroducerSizes()' name
  double period_s = 0.001;
  std::vector<SessionSample> samples;
  std::vector<SessionEvent> events;
};

/// Runs a session: the scene, the device and the introducer must outlive it.
class TrainerSession {
 public:
  /// Buffers for `capacity` ticks (a tick beyond them is run but not recorded: `dropped()`).
  TrainerSession(const TrainerScene& scene, HapticDevice* device, const Introducer& introducer,
                 const ProxyOptions& options, double period_s, std::int64_t capacity);
  /// One servo tick at `time_s`: no allocation, lock, throw or I/O.
  void Tick(double time_s) noexcept;
  const SessionRecord& record() const { return record_; }
  std::int64_t dropped() const { return dropped_; }
  const GodObject& proxy() const { return proxy_; }

 private:
  HapticDevice* device_;
  GodObject proxy_;
  SessionRecord record_;
  std::uint32_t last_organs_ = 0;
  std::int64_t dropped_ = 0;
  bool started_ = false;
};

/// Runs `device` for `duration_s` in simulated time (ticks at k period_s), returning the record.
SessionRecord RunSession(const TrainerScene& scene, HapticDevice* device, const Introducer& introducer,
                         const ProxyOptions& options, double duration_s, double period_s = 0.001);
/// Replays a record: its device states through a ScriptedDevice at its own tick times.
SessionRecord ReplaySession(const TrainerScene& scene, const SessionRecord& record,
                            const ProxyOptions& options = {});

/// The introducer of that name (Error(kBadInput) if none).
const Introducer& IntroducerNamed(const std::string& name);

/// The record as text (docs/trainer.md, "Session records"): a header, one line per tick, one per event,
/// numbers with 17 significant digits.
std::string FormatSessionRecord(const SessionRecord& record);
/// Reads FormatSessionRecord's text back (bit for bit). Throws Error(kBadInput) naming `source` and the line.
SessionRecord ParseSessionRecord(const std::string& text, const std::string& source);
/// Writes atomically / reads a record file.
void WriteSessionRecord(const std::filesystem::path& path, const SessionRecord& record);
SessionRecord ReadSessionRecord(const std::filesystem::path& path);

}  // namespace pectus::trainer
