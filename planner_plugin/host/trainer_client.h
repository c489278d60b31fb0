// pectus planner host: a patient's Nuss trainer through the plugin (interface version 5), as C++ (RAII,
// pectus::Error on failure, Eigen arrays): the scene to draw, a session on the plugin's servo thread
// ticking the host's device, its latest tick, scores, record and replay, the thoracoscope's view. Nothing
// here knows how the plugin renders the haptics; it only speaks planner_api.h (docs/trainer.md).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <filesystem>
#include <string>

#include "planner_plugin/api/planner_api.h"
#include "planner_plugin/host/planner_client.h"
#include "shape/core/geometry.h"

namespace pectus::planner {

/// A patient's trainer (made on construction from the patient's planner, destroyed with this object; the
/// planner may go first).
class TrainerClient {
 public:
  /// Builds the scene (seconds). `introducer`: "small", "medium" or "large". Throws the plugin's error.
  TrainerClient(const PlannerClient& planner, const PlannerPlugin& plugin, const std::string& introducer,
                std::int64_t capacity_ticks = 0);
  ~TrainerClient();
  TrainerClient(const TrainerClient&) = delete;
  TrainerClient& operator=(const TrainerClient&) = delete;

  /// The scene's meshes: 0 bones, 1 pericardium, 2 right lung, 3 left lung.
  TriangleMesh Mesh(int part) const;
  const PectusPlannerTunnel& tunnel() const { return tunnel_; }
  /// The tunnel's polyline, #points by 3, right port first.
  const Points3& tunnel_points() const { return tunnel_points_; }

  /// A new session on the plugin's servo thread reading `device` (which must outlive Stop()).
  void Start(const PectusPlannerDevice& device, double rate_hz = 1000);
  PectusPlannerLoopStatistics Stop();
  /// The latest tick; false before the first.
  bool Latest(PectusPlannerTrainerTick* out) const;
  /// The scores of the ticks so far; false for fewer than two ticks.
  bool Score(PectusPlannerTrainerScore* out) const;
  void WriteRecord(const std::filesystem::path& path) const;
  /// The record at `path` replayed in this scene, scored.
  PectusPlannerTrainerScore Replay(const std::filesystem::path& path) const;
  /// The scope's view aimed at `target_mm`, from `insertion_mm` in.
  PectusPlannerScopeView ScopeViewAt(const Eigen::Vector3d& target_mm, double insertion_mm) const;

 private:
  const PectusPlannerInterface* api_;
  PectusPlannerTrainer* trainer_ = nullptr;
  PectusPlannerTunnel tunnel_{};
  Points3 tunnel_points_;
};

}  // namespace pectus::planner
