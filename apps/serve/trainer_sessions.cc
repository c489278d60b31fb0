#include "apps/serve/trainer_sessions.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <sstream>

#include "shape/core/error.h"

namespace pectus::serve {

namespace {

using nlohmann::json;
using Clock = std::chrono::steady_clock;

json Vec(const double* v) { return {v[0], v[1], v[2]}; }
json Vec(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }

json SpaceJson(const PectusPlannerSpace& s) {
  const std::string name =
      s.side == 0 || s.number == 0 ? "none" : (s.side < 0 ? "right " : "left ") + std::to_string(s.number);
  return {{"side", s.side}, {"number", s.number}, {"name", name}};
}

json OrgansJson(std::uint32_t organs) {
  json out = json::array();
  static const char* kNames[] = {"bone", "pericardium", "lung"};
  for (int k = 0; k < 3; ++k)
    if (organs >> k & 1u) out.push_back(kNames[k]);
  return out;
}

void AppendMesh(std::string* out, const TriangleMesh& mesh) {
  const Points3& v = mesh.vertices.positions;
  for (Eigen::Index i = 0; i < v.size(); ++i) {
    const auto f = static_cast<float>(v.data()[i]);
    out->append(reinterpret_cast<const char*>(&f), 4);
  }
  for (Eigen::Index i = 0; i < mesh.faces.size(); ++i) {
    const auto u = static_cast<std::uint32_t>(mesh.faces.data()[i]);
    out->append(reinterpret_cast<const char*>(&u), 4);
  }
}

std::string ReadText(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

}  // namespace

json TrainerScoreJson(const PectusPlannerTrainerScore& s, const PectusPlannerTunnel& tunnel) {
  return {{"score", s.score},
          {"ticks", s.ticks},
          {"total_time_s", s.total_time_s},
          {"min_pericardium_distance_mm", s.min_pericardium_distance_mm},
          {"time_near_pericardium_s", s.time_near_pericardium_s},
          {"pericardial_contacts", s.pericardial_contacts},
          {"peak_pericardium_force_n", s.peak_pericardium_force_n},
          {"peak_force_n", s.peak_force_n},
          {"path_length_mm", s.path_length_mm},
          {"rms_tunnel_deviation_mm", s.rms_tunnel_deviation_mm},
          {"entry", SpaceJson(s.entry)},
          {"exit", SpaceJson(s.exit)},
          {"planned_entry", SpaceJson(tunnel.entry)},
          {"planned_exit", SpaceJson(tunnel.exit)},
          {"entry_as_planned", s.entry_as_planned != 0},
          {"exit_as_planned", s.exit_as_planned != 0}};
}

// ---- the device ----------------------------------------------------------------------------------------

PointerDevice::PointerDevice(const Eigen::Vector3d& start_mm, const Eigen::Vector3d& axis)
    : from_(start_mm),
      to_(start_mm),
      anchor_(start_mm - 20.0 * axis.normalized()),
      moved_at_(Clock::now()),
      previous_move_(moved_at_) {
  last_ = StateAt(moved_at_);
}

void PointerDevice::MoveTo(const Eigen::Vector3d& target_mm, std::uint32_t buttons) {
  std::lock_guard<std::mutex> lock(mutex_);
  const Clock::time_point now = Clock::now();
  // Glide from where the device is now to the target over the time between messages, so that at the
  // page's pace the servo loop sees the hand move continuously.
  const double since = std::chrono::duration<double>(now - moved_at_).count();
  const double s = std::clamp(since / glide_s_, 0.0, 1.0);
  from_ = from_ + s * (to_ - from_);
  to_ = target_mm;
  glide_s_ = std::clamp(since, 0.005, 0.1);
  moved_at_ = now;
  buttons_ = buttons;
  has_orientation_ = false;
  // The shaft trails the tip: the anchor follows at 20 mm along the path (follow the leader).
  const Eigen::Vector3d d = to_ - anchor_;
  if (d.norm() > 20.0) anchor_ = to_ - 20.0 * d.normalized();
}

void PointerDevice::Set(const Eigen::Vector3d& position_mm, const Eigen::Quaterniond& orientation,
                        std::uint32_t buttons) {
  std::lock_guard<std::mutex> lock(mutex_);
  from_ = to_ = position_mm;
  moved_at_ = Clock::now();
  buttons_ = buttons;
  orientation_ = orientation;
  has_orientation_ = true;
  const Eigen::Vector3d d = to_ - anchor_;
  if (d.norm() > 20.0) anchor_ = to_ - 20.0 * d.normalized();
}

PectusPlannerDeviceState PointerDevice::StateAt(Clock::time_point now) {
  const double since = std::chrono::duration<double>(now - moved_at_).count();
  const double s = std::clamp(since / glide_s_, 0.0, 1.0);
  const Eigen::Vector3d p = from_ + s * (to_ - from_);
  Eigen::Vector3d axis = p - anchor_;
  if (axis.norm() < 1e-6) axis = Eigen::Vector3d::UnitX();
  const Eigen::Quaterniond q =
      has_orientation_ ? orientation_
                       : Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitZ(), axis.normalized());
  PectusPlannerDeviceState out{};
  for (int k = 0; k < 3; ++k) out.position_mm[k] = p[k];
  out.orientation_wxyz[0] = q.w();
  out.orientation_wxyz[1] = q.x();
  out.orientation_wxyz[2] = q.y();
  out.orientation_wxyz[3] = q.z();
  out.buttons = buttons_;
  return out;
}

void PointerDevice::Read(void* user, double time_s, PectusPlannerDeviceState* out) {
  auto* d = static_cast<PointerDevice*>(user);
  if (d->mutex_.try_lock()) {  // never waits on an HTTP thread
    d->last_ = d->StateAt(Clock::now());
    d->mutex_.unlock();
  }
  *out = d->last_;
  out->time_s = time_s;
}

PectusPlannerDevice PointerDevice::Callbacks() {
  return {this, &PointerDevice::Read, &PointerDevice::SetForce};
}

// ---- the sessions
// -------------------------------------------------------------------------------------------

struct TrainerSessions::Session {
  std::mutex mutex;  // one request at a time per session
  std::string id, patient, introducer;
  std::unique_ptr<planner::TrainerClient> trainer;
  std::unique_ptr<PointerDevice> device;
  bool running = false;
  Clock::time_point last_used = Clock::now(), scored_at{};
  json score = nullptr, report = nullptr;
  std::string record;  // after Finish

  json FinishLocked(const std::filesystem::path& work_dir);
};

TrainerSessions::TrainerSessions(const planner::PlannerPlugin& plugin, std::filesystem::path work_dir,
                                 int max_sessions, double idle_s)
    : plugin_(plugin), work_dir_(std::move(work_dir)), max_sessions_(max_sessions), idle_s_(idle_s) {}

TrainerSessions::~TrainerSessions() {
  std::lock_guard<std::mutex> lock(mutex_);
  for (auto& [id, s] : sessions_) {
    std::lock_guard<std::mutex> session_lock(s->mutex);
    if (s->running) s->trainer->Stop();
    s->running = false;
  }
}

json TrainerSessions::Session::FinishLocked(const std::filesystem::path& work_dir) {
  if (!report.is_null()) return report;
  const PectusPlannerLoopStatistics loop = running ? trainer->Stop() : PectusPlannerLoopStatistics{};
  running = false;
  PectusPlannerTrainerScore score_now{};
  if (!trainer->Score(&score_now)) {
    report = {{"session", id}, {"error", "the session ended before two ticks"}};
    return report;
  }
  // The record, written and replayed: the scores a replay gives are the session's, to the bit.
  std::filesystem::create_directories(work_dir);
  const std::filesystem::path path = work_dir / ("trainer_session_" + id + ".txt");
  trainer->WriteRecord(path);
  const PectusPlannerTrainerScore replayed = trainer->Replay(path);
  record = ReadText(path);
  std::filesystem::remove(path);
  report = {{"session", id},
            {"patient", patient},
            {"introducer", introducer},
            {"score", TrainerScoreJson(score_now, trainer->tunnel())},
            {"replay_gives_the_same_scores", std::memcmp(&replayed, &score_now, sizeof(replayed)) == 0},
            {"loop",
             {{"ticks", loop.ticks},
              {"late_ticks", loop.late_ticks},
              {"period_mean_ms", loop.period_mean_ms},
              {"period_p99_ms", loop.period_p99_ms},
              {"period_max_ms", loop.period_max_ms},
              {"tick_p99_us", loop.tick_p99_us}}},
            {"record", "/api/trainer/" + id + "/record"},
            {"level_z_mm", trainer->tunnel().level_z_mm}};
  return report;
}

void TrainerSessions::Expire() {
  // Under mutex_: the idle sessions are finished (their servo threads stopped), kept for their reports.
  const Clock::time_point now = Clock::now();
  for (auto& [id, s] : sessions_) {
    std::unique_lock<std::mutex> lock(s->mutex, std::try_to_lock);
    if (lock && s->running && std::chrono::duration<double>(now - s->last_used).count() > idle_s_)
      s->FinishLocked(work_dir_);
  }
}

json TrainerSessions::Start(const planner::PlannerClient& planner, const std::string& patient,
                            const std::string& introducer) {
  auto s = std::make_shared<Session>();
  s->patient = patient;
  s->introducer = introducer;
  s->trainer = std::make_unique<planner::TrainerClient>(planner, plugin_, introducer);
  const PectusPlannerTunnel& t = s->trainer->tunnel();
  const Points3& points = s->trainer->tunnel_points();
  // The device starts 25 mm outside the entry port, the shaft pointing in along the tunnel's start.
  const Eigen::Vector3d entry(t.entry_port_mm[0], t.entry_port_mm[1], t.entry_port_mm[2]);
  const Eigen::Index inside = std::min<Eigen::Index>(5, points.rows() - 1);
  Eigen::Vector3d outward = entry - points.row(inside).transpose();
  if (outward.norm() < 1e-6) outward = -Eigen::Vector3d::UnitX();
  outward.normalize();
  const Eigen::Vector3d start = entry + 25.0 * outward;
  s->device = std::make_unique<PointerDevice>(start, -outward);
  {
    std::lock_guard<std::mutex> lock(mutex_);
    Expire();
    s->id = std::to_string(next_++);
    // Room for the new one: the oldest sessions go (finished first).
    while (static_cast<int>(sessions_.size()) >= max_sessions_) {
      auto oldest = sessions_.begin();
      std::lock_guard<std::mutex> lock_oldest(oldest->second->mutex);
      if (oldest->second->running) oldest->second->trainer->Stop();
      oldest->second->running = false;
      sessions_.erase(oldest);
    }
    sessions_[s->id] = s;
  }
  std::lock_guard<std::mutex> lock(s->mutex);
  s->trainer->Start(s->device->Callbacks());
  s->running = true;
  json tunnel_points = json::array();
  for (Eigen::Index i = 0; i < points.rows(); ++i)
    tunnel_points.push_back(Vec(Eigen::Vector3d(points.row(i))));
  json meshes = json::object();
  const char* names[] = {"pericardium", "right_lung", "left_lung"};
  for (int part = 1; part <= 3; ++part) {
    const TriangleMesh m = s->trainer->Mesh(part);
    meshes[names[part - 1]] = {{"vertices", m.num_vertices()}, {"faces", m.num_faces()}};
  }
  return {{"session", s->id},
          {"patient", patient},
          {"introducer", introducer},
          {"start_mm", Vec(start)},
          {"tunnel",
           {{"points", tunnel_points},
            {"entry_port_mm", Vec(t.entry_port_mm)},
            {"exit_port_mm", Vec(t.exit_port_mm)},
            {"scope_port_mm", Vec(t.scope_port_mm)},
            {"entry", SpaceJson(t.entry)},
            {"exit", SpaceJson(t.exit)},
            {"level_z_mm", t.level_z_mm},
            {"length_mm", t.length_mm}}},
          {"meshes", meshes}};
}

std::shared_ptr<TrainerSessions::Session> TrainerSessions::Find(const std::string& id) {
  std::lock_guard<std::mutex> lock(mutex_);
  Expire();
  const auto it = sessions_.find(id);
  if (it == sessions_.end())
    ThrowUsage("no trainer session '" + id + "' (finished long ago, or never started)");
  return it->second;
}

std::string TrainerSessions::Meshes(const std::string& id) {
  const auto s = Find(id);
  std::lock_guard<std::mutex> lock(s->mutex);
  std::string out;
  for (int part = 1; part <= 3; ++part) AppendMesh(&out, s->trainer->Mesh(part));
  return out;
}

json TrainerSessions::Device(const std::string& id, const Eigen::Vector3d& position_mm,
                             std::uint32_t buttons) {
  const auto s = Find(id);
  std::lock_guard<std::mutex> lock(s->mutex);
  s->last_used = Clock::now();
  if (!s->running) ThrowUsage("trainer session " + id + " is finished");
  s->device->MoveTo(position_mm, buttons);
  json out = {{"session", id}};
  PectusPlannerTrainerTick t{};
  if (s->trainer->Latest(&t)) {
    out["tick"] = {{"tick", t.tick},
                   {"time_s", t.time_s},
                   {"device_mm", Vec(t.device_mm)},
                   {"proxy_mm", Vec(t.proxy_mm)},
                   {"axis", Vec(t.axis)},
                   {"force_n", Vec(t.force_n)},
                   {"organs", OrgansJson(t.organs_touched)},
                   {"pericardium_force_n", t.pericardium_force_n},
                   {"pericardium_distance_mm", t.pericardium_distance_mm}};
    // The scope, held by an assistant who keeps the introducer's tip in the middle of its view; it goes in
    // less far for a tip near its port (the aim needs the tip beyond the scope's own tip).
    const PectusPlannerTunnel& tunnel = s->trainer->tunnel();
    const Eigen::Vector3d port(tunnel.scope_port_mm[0], tunnel.scope_port_mm[1], tunnel.scope_port_mm[2]);
    const Eigen::Vector3d tip(t.proxy_mm[0], t.proxy_mm[1], t.proxy_mm[2]);
    const double insertion = std::clamp(0.4 * (tip - port).norm(), 5.0, 40.0);
    const PectusPlannerScopeView v = s->trainer->ScopeViewAt(tip, insertion);
    out["scope"] = {{"eye_mm", Vec(v.eye_mm)},
                    {"forward", Vec(v.forward)},
                    {"up", Vec(v.up)},
                    {"vertical_fov_deg", v.vertical_fov_deg},
                    {"aspect", static_cast<double>(v.width_px) / v.height_px},
                    {"insertion_mm", v.insertion_mm}};
  }
  const Clock::time_point now = Clock::now();
  if (s->score.is_null() || now - s->scored_at > std::chrono::milliseconds(200)) {
    PectusPlannerTrainerScore score{};
    if (s->trainer->Score(&score)) {
      s->score = TrainerScoreJson(score, s->trainer->tunnel());
      s->scored_at = now;
    }
  }
  out["score"] = s->score;
  return out;
}

std::uint32_t TrainerSessions::DriverMove(const std::string& id, const Eigen::Vector3d& position_mm,
                                          const Eigen::Quaterniond& orientation, std::uint32_t buttons,
                                          PectusPlannerTrainerTick* tick) {
  std::shared_ptr<Session> s;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    const auto it = sessions_.find(id);
    if (it == sessions_.end()) return 1;
    s = it->second;
  }
  std::lock_guard<std::mutex> lock(s->mutex);
  if (!s->running) return 3;
  s->last_used = Clock::now();
  s->device->Set(position_mm, orientation, buttons);
  if (!s->trainer->Latest(tick)) *tick = PectusPlannerTrainerTick{};
  return 0;
}

json TrainerSessions::Finish(const std::string& id) {
  const auto s = Find(id);
  std::lock_guard<std::mutex> lock(s->mutex);
  return s->FinishLocked(work_dir_);
}

std::string TrainerSessions::Record(const std::string& id) {
  const auto s = Find(id);
  std::lock_guard<std::mutex> lock(s->mutex);
  if (s->report.is_null())
    ThrowUsage("trainer session " + id + " is not finished: its record is not complete");
  return s->record;
}

}  // namespace pectus::serve
