#include "planner_plugin/host/trainer_client.h"

#include "shape/core/error.h"

namespace pectus::planner {

TrainerClient::TrainerClient(const PlannerClient& planner, const PlannerPlugin& plugin,
                             const std::string& introducer, std::int64_t capacity_ticks)
    : api_(&plugin.api()) {
  PectusPlannerStatus status{};
  ThrowIfFailed(
      api_->trainer_create(planner.handle(), introducer.c_str(), capacity_ticks, &trainer_, &status), status);
  try {
    ThrowIfFailed(api_->trainer_tunnel(trainer_, &tunnel_, nullptr, 0, &status), status);
    tunnel_points_.resize(tunnel_.num_points, 3);
    ThrowIfFailed(api_->trainer_tunnel(trainer_, nullptr, tunnel_points_.data(), tunnel_.num_points, &status),
                  status);
  } catch (...) {
    api_->trainer_destroy(trainer_);
    throw;
  }
}

TrainerClient::~TrainerClient() { api_->trainer_destroy(trainer_); }

TriangleMesh TrainerClient::Mesh(int part) const {
  PectusPlannerStatus status{};
  PectusPlannerMesh m{};
  ThrowIfFailed(api_->trainer_mesh(trainer_, part, &m, &status), status);
  TriangleMesh mesh;
  mesh.vertices.positions = Eigen::Map<const Points3>(m.vertices, m.num_vertices, 3);
  mesh.faces = Eigen::Map<const Faces3>(m.faces, m.num_faces, 3);
  return mesh;
}

void TrainerClient::Start(const PectusPlannerDevice& device, double rate_hz) {
  PectusPlannerStatus status{};
  ThrowIfFailed(api_->trainer_start(trainer_, &device, rate_hz, &status), status);
}

PectusPlannerLoopStatistics TrainerClient::Stop() {
  PectusPlannerStatus status{};
  PectusPlannerLoopStatistics out{};
  ThrowIfFailed(api_->trainer_stop(trainer_, &out, &status), status);
  return out;
}

bool TrainerClient::Latest(PectusPlannerTrainerTick* out) const {
  PectusPlannerStatus status{};
  return api_->trainer_latest(trainer_, out, &status) == PECTUS_PLANNER_OK;
}

bool TrainerClient::Score(PectusPlannerTrainerScore* out) const {
  PectusPlannerStatus status{};
  const std::int32_t code = api_->trainer_score(trainer_, out, &status);
  if (code == PECTUS_PLANNER_USAGE) return false;  // fewer than two ticks
  ThrowIfFailed(code, status);
  return true;
}

void TrainerClient::WriteRecord(const std::filesystem::path& path) const {
  PectusPlannerStatus status{};
  ThrowIfFailed(api_->trainer_write_record(trainer_, path.c_str(), &status), status);
}

PectusPlannerTrainerScore TrainerClient::Replay(const std::filesystem::path& path) const {
  PectusPlannerStatus status{};
  PectusPlannerTrainerScore out{};
  ThrowIfFailed(api_->trainer_replay(trainer_, path.c_str(), &out, &status), status);
  return out;
}

PectusPlannerScopeView TrainerClient::ScopeViewAt(const Eigen::Vector3d& target_mm,
                                                  double insertion_mm) const {
  PectusPlannerStatus status{};
  PectusPlannerScopeView out{};
  const double target[3] = {target_mm.x(), target_mm.y(), target_mm.z()};
  ThrowIfFailed(api_->trainer_scope_view(trainer_, nullptr, target, insertion_mm, &out, &status), status);
  return out;
}

}  // namespace pectus::planner
