#include "planner_plugin/plugin/planner_trainer.h"

#include <cmath>

#include "shape/core/error.h"

namespace pectus::planner {

namespace {

trainer::DeviceState StateFrom(const PectusPlannerDeviceState& s) {
  trainer::DeviceState d;
  d.time_s = s.time_s;
  d.position_mm = Eigen::Vector3d(s.position_mm[0], s.position_mm[1], s.position_mm[2]);
  d.orientation = Eigen::Quaterniond(s.orientation_wxyz[0], s.orientation_wxyz[1], s.orientation_wxyz[2],
                                     s.orientation_wxyz[3]);
  d.buttons = s.buttons;
  return d;
}

bool Finite(const PectusPlannerDeviceState& s) {
  bool ok = std::isfinite(s.time_s);
  for (double v : s.position_mm) ok = ok && std::isfinite(v);
  double norm = 0;
  for (double v : s.orientation_wxyz) {
    ok = ok && std::isfinite(v);
    norm += v * v;
  }
  return ok && norm > 1e-12;
}

// A unit quaternion is kept as it is, to the bit (a session replays its device's states exactly).
void Normalise(Eigen::Quaterniond* q) {
  if (std::abs(q->squaredNorm() - 1.0) > 1e-12) q->normalize();
}

void Copy3(const Eigen::Vector3d& v, double* out) {
  out[0] = v.x();
  out[1] = v.y();
  out[2] = v.z();
}

}  // namespace

trainer::DeviceState HostDevice::Read(double time_s) noexcept {
  if (callbacks_.read != nullptr) {
    PectusPlannerDeviceState s{};
    s.time_s = time_s;
    s.orientation_wxyz[0] = 1;
    callbacks_.read(callbacks_.user, time_s, &s);
    if (!Finite(s)) {
      // A reading the proxy can take: it renders no force and stays where it was.
      last_ = trainer::DeviceState();
      last_.time_s = time_s;
      last_.position_mm.setConstant(std::nan(""));
      return last_;
    }
    last_ = StateFrom(s);
    last_.time_s = time_s;
    Normalise(&last_.orientation);
    return last_;
  }
  last_ = held_;
  return last_;
}

void HostDevice::SetForceAndTorque(const Eigen::Vector3d& force_n,
                                   const Eigen::Vector3d& torque_nmm) noexcept {
  if (callbacks_.set_force == nullptr) return;
  const double f[3] = {force_n.x(), force_n.y(), force_n.z()};
  const double t[3] = {torque_nmm.x(), torque_nmm.y(), torque_nmm.z()};
  callbacks_.set_force(callbacks_.user, f, t);
}

PlannerTrainer::PlannerTrainer(const PatientRibcage& ribcage, const std::string& introducer,
                               std::int64_t capacity_ticks)
    : scene_(trainer::BuildTrainerScene(ribcage)),
      introducer_(&trainer::IntroducerNamed(introducer)),
      capacity_(capacity_ticks == 0 ? 600000 : capacity_ticks) {
  if (capacity_ticks < 0) ThrowUsage("trainer: capacity_ticks must be >= 0 (0: ten minutes at 1 kHz)");
  // The scope's port: the right space below the planned entry (the thoracoscope goes in one space below
  // the introducer's incision), or above it, or the entry itself.
  const trainer::IntercostalSpace entry = scene_.tunnel.entry;
  scope_port_ = scene_.tunnel.entry_port;
  for (int offset : {+1, -1}) {
    bool found = false;
    for (const auto& [space, centre] : scene_.ports) {
      if (space.side == entry.side && space.number == entry.number + offset) {
        scope_port_ = centre;
        found = true;
        break;
      }
    }
    if (found) break;
  }
  Reset();
}

PlannerTrainer::~PlannerTrainer() { Stop(); }

void PlannerTrainer::Reset() {
  if (running()) ThrowUsage("trainer: stop the servo thread before starting a new session");
  committed_samples_.store(0);
  committed_events_.store(0);
  {
    std::lock_guard<std::mutex> lock(latest_mutex_);
    has_latest_ = false;
  }
  last_time_s_ = -INFINITY;
  device_.UseHeld();
  session_ = std::make_unique<trainer::TrainerSession>(scene_, &device_, *introducer_,
                                                       trainer::ProxyOptions{}, 0.001, capacity_);
}

void PlannerTrainer::TickAndPublish(double time_s) noexcept {
  session_->Tick(time_s);
  last_time_s_ = time_s;
  const trainer::SessionRecord& r = session_->record();
  committed_samples_.store(static_cast<std::int64_t>(r.samples.size()), std::memory_order_release);
  committed_events_.store(static_cast<std::int64_t>(r.events.size()), std::memory_order_release);
  const trainer::ProxyContact& c = session_->proxy().contact();
  PectusPlannerTrainerTick t{};
  t.tick = static_cast<std::int64_t>(r.samples.size()) + session_->dropped();
  t.time_s = time_s;
  Copy3(c.goal_mm, t.device_mm);
  Copy3(c.proxy_mm, t.proxy_mm);
  Copy3(device_.last().orientation * Eigen::Vector3d::UnitZ(), t.axis);
  Copy3(c.force_n, t.force_n);
  Copy3(c.torque_nmm, t.torque_nmm);
  t.organs_touched = c.organs_touched;
  t.pericardium_force_n = c.pericardium_force_n;
  t.pericardium_distance_mm = scene_.DistanceToPericardium(c.proxy_mm);
  if (latest_mutex_.try_lock()) {  // never waits: a reader copying it costs this tick's publication only
    latest_ = t;
    has_latest_ = true;
    latest_mutex_.unlock();
  }
}

bool PlannerTrainer::Tick(const PectusPlannerDeviceState& state, PectusPlannerTrainerTick* out,
                          const char** why) noexcept {
  if (running()) {
    *why = "trainer_tick: the servo thread is running (trainer_stop first)";
    return false;
  }
  if (!Finite(state)) {
    *why = "trainer_tick: the device state is not finite (or its orientation is zero)";
    return false;
  }
  if (state.time_s < last_time_s_) {
    *why = "trainer_tick: time went back (a tick's time_s must not be below the last tick's)";
    return false;
  }
  trainer::DeviceState d = StateFrom(state);
  Normalise(&d.orientation);
  device_.Hold(d);
  TickAndPublish(state.time_s);
  if (out != nullptr) {
    std::lock_guard<std::mutex> lock(latest_mutex_);  // uncontended: this thread is the only writer
    *out = latest_;
  }
  return true;
}

void PlannerTrainer::Start(const PectusPlannerDevice& device, double rate_hz) {
  if (device.read == nullptr) ThrowUsage("trainer_start: the device has no read function");
  if (!(rate_hz > 0 && rate_hz <= 20000)) ThrowUsage("trainer_start: rate_hz must be in (0, 20000]");
  Reset();
  device_.UseCallbacks(device);
  trainer::ServoLoopOptions options;
  options.rate_hz = rate_hz;
  options.max_records = static_cast<std::int64_t>(std::min<double>(capacity_, 1e6));
  loop_ = std::make_unique<trainer::ServoLoop>(options);
  loop_->Start([this](double time_s) { TickAndPublish(time_s); });
}

trainer::ServoLoopStatistics PlannerTrainer::Stop() {
  if (!loop_) return {};
  loop_->Stop();
  trainer::ServoLoopStatistics statistics = loop_->Statistics();
  loop_.reset();
  device_.UseHeld();
  return statistics;
}

bool PlannerTrainer::Latest(PectusPlannerTrainerTick* out) const {
  std::lock_guard<std::mutex> lock(latest_mutex_);
  if (!has_latest_) return false;
  *out = latest_;
  return true;
}

trainer::SessionRecord PlannerTrainer::RecordSoFar() const {
  // The counts first (acquire): the samples and events below them are complete and stay as they are.
  const std::int64_t n = committed_samples_.load(std::memory_order_acquire);
  const std::int64_t m = committed_events_.load(std::memory_order_acquire);
  const trainer::SessionRecord& r = session_->record();
  trainer::SessionRecord out;
  out.patient = r.patient;
  out.introducer = r.introducer;
  out.period_s = r.period_s;
  out.samples.assign(r.samples.data(), r.samples.data() + n);
  out.events.assign(r.events.data(), r.events.data() + m);
  return out;
}

trainer::SessionScore PlannerTrainer::Score() const {
  const trainer::SessionRecord record = RecordSoFar();
  if (record.samples.size() < 2) ThrowUsage("trainer_score: the session has fewer than two ticks");
  return trainer::ScoreSession(scene_, record);
}

PectusPlannerScopeView PlannerTrainer::ScopeView(const Eigen::Quaterniond* orientation,
                                                 const Eigen::Vector3d& target, double insertion_mm) const {
  if (!(insertion_mm > 0 && insertion_mm < 500))
    ThrowUsage("trainer_scope_view: insertion_mm must be in (0, 500)");
  trainer::ScopePose pose;
  pose.port_mm = scope_port_;
  pose.insertion_mm = insertion_mm;
  const Eigen::Matrix3d scope_from_camera = camera_.ScopeFromCamera();
  if (orientation != nullptr) {
    if (!(orientation->coeffs().allFinite() && orientation->norm() > 1e-12))
      ThrowUsage("trainer_scope_view: the orientation is not a finite, non-zero quaternion");
    pose.orientation = orientation->normalized();
  } else {
    if (!target.allFinite()) ThrowUsage("trainer_scope_view: the target is not finite");
    // Aim: the camera looks from the tip at the target with the image's up towards the head (+z), the
    // scope's R = R_scene_camera R_scope_camera^T; the tip moves with R, so a few rounds (each moves it by
    // less than the last: the port is a fixed point and the target is further than the insertion).
    Eigen::Vector3d tip = scope_port_;
    for (int round = 0; round < 20; ++round) {
      Eigen::Vector3d w = target - tip;
      if (w.norm() < 1e-6) w = target - scope_port_;
      if (w.norm() < 1e-6) w = Eigen::Vector3d(1, 0, 0);
      w.normalize();
      Eigen::Vector3d up = Eigen::Vector3d::UnitZ() - Eigen::Vector3d::UnitZ().dot(w) * w;
      if (up.norm() < 1e-6) up = Eigen::Vector3d::UnitY() - Eigen::Vector3d::UnitY().dot(w) * w;
      up.normalize();
      Eigen::Matrix3d scene_from_camera;
      scene_from_camera.col(2) = w;
      scene_from_camera.col(1) = -up;  // the image's y points down
      scene_from_camera.col(0) = scene_from_camera.col(1).cross(w);
      pose.orientation = Eigen::Quaterniond(scene_from_camera * scope_from_camera.transpose()).normalized();
      const Eigen::Vector3d next = pose.Tip();
      const double moved = (next - tip).norm();
      tip = next;
      if (moved < 1e-9) break;
    }
  }
  const Eigen::Isometry3d camera = camera_.SceneFromCamera(pose);
  PectusPlannerScopeView v{};
  v.orientation_wxyz[0] = pose.orientation.w();
  v.orientation_wxyz[1] = pose.orientation.x();
  v.orientation_wxyz[2] = pose.orientation.y();
  v.orientation_wxyz[3] = pose.orientation.z();
  v.insertion_mm = insertion_mm;
  Copy3(camera.translation(), v.eye_mm);
  Copy3(camera.linear().col(2), v.forward);
  Copy3(-camera.linear().col(1), v.up);
  const trainer::ScopeCameraOptions& o = camera_.options();
  v.horizontal_fov_deg = o.horizontal_fov_deg;
  v.vertical_fov_deg = 2 * std::atan(0.5 * o.height_px / camera_.focal_px()) * 180 / M_PI;
  v.width_px = o.width_px;
  v.height_px = o.height_px;
  v.focal_px = camera_.focal_px();
  return v;
}

}  // namespace pectus::planner
