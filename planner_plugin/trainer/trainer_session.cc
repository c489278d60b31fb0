#include "planner_plugin/trainer/trainer_session.h"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

#include "shape/core/atomic_file.h"
#include "shape/core/error.h"

namespace pectus::trainer {

TrainerSession::TrainerSession(const TrainerScene& scene, HapticDevice* device, const Introducer& introducer,
                               const ProxyOptions& options, double period_s, std::int64_t capacity)
    : device_(device), proxy_(scene, introducer, options) {
  if (device == nullptr) ThrowUsage("trainer session: no device");
  if (!(period_s > 0) || capacity < 1) ThrowUsage("trainer session: period must be > 0 and capacity >= 1");
  record_.patient = scene.patient;
  record_.introducer = introducer.name;
  record_.period_s = period_s;
  record_.samples.reserve(static_cast<std::size_t>(capacity));
  record_.events.reserve(4096);
}

void TrainerSession::Tick(double time_s) noexcept {
  const DeviceState state = device_->Read(time_s);
  if (!started_) {
    proxy_.Reset(state.position_mm);
    started_ = true;
  }
  const ProxyContact& c = proxy_.Update(state.position_mm, state.orientation, record_.period_s);
  device_->SetForceAndTorque(c.force_n, c.torque_nmm);
  if (record_.samples.size() == record_.samples.capacity()) {
    ++dropped_;
    return;
  }
  record_.samples.push_back({time_s, state.position_mm, state.orientation, c.proxy_mm, c.force_n,
                             c.organs_touched, c.pericardium_force_n});
  const std::uint32_t changed = c.organs_touched ^ last_organs_;
  for (int organ = 0; organ < kNumOrgans; ++organ) {
    if ((changed >> organ & 1u) && record_.events.size() < record_.events.capacity()) {
      record_.events.push_back({time_s, organ, (c.organs_touched >> organ & 1u) != 0});
    }
  }
  last_organs_ = c.organs_touched;
}

SessionRecord RunSession(const TrainerScene& scene, HapticDevice* device, const Introducer& introducer,
                         const ProxyOptions& options, double duration_s, double period_s) {
  const auto ticks = static_cast<std::int64_t>(std::floor(duration_s / period_s + 1e-9)) + 1;
  TrainerSession session(scene, device, introducer, options, period_s, ticks);
  for (std::int64_t k = 0; k < ticks; ++k) session.Tick(static_cast<double>(k) * period_s);
  return session.record();
}

const Introducer& IntroducerNamed(const std::string& name) {
  for (const Introducer& i : IntroducerSizes()) {
    if (name == i.name) return i;
  }
  ThrowBadInput("session record", "unknown introducer '" + name + "' (small, medium or large)");
}

SessionRecord ReplaySession(const TrainerScene& scene, const SessionRecord& record,
                            const ProxyOptions& options) {
  Trajectory t;
  t.samples.reserve(record.samples.size());
  for (const SessionSample& s : record.samples) {
    DeviceState d;
    d.time_s = s.time_s;
    d.position_mm = s.device_mm;
    d.orientation = s.orientation;
    t.samples.push_back(d);
  }
  ScriptedDevice device(std::move(t));
  TrainerSession session(scene, &device, IntroducerNamed(record.introducer), options, record.period_s,
                         static_cast<std::int64_t>(record.samples.size()));
  for (const SessionSample& s : record.samples) session.Tick(s.time_s);
  return session.record();
}

std::string FormatSessionRecord(const SessionRecord& r) {
  std::string out = "# pectus trainer session\n";
  char line[700];
  std::snprintf(line, sizeof(line), "patient %s\nintroducer %s\nperiod_s %.17g\n", r.patient.c_str(),
                r.introducer.c_str(), r.period_s);
  out += line;
  out +=
      "# tick t_s device_x device_y device_z qw qx qy qz proxy_x proxy_y proxy_z force_x force_y force_z "
      "organs "
      "pericardium_force_n\n";
  for (const SessionSample& s : r.samples) {
    const Eigen::Quaterniond& q = s.orientation;
    std::snprintf(
        line, sizeof(line),
        "tick %.17g %.17g %.17g %.17g %.17g %.17g %.17g %.17g %.17g %.17g %.17g %.17g %.17g %.17g %u %.17g\n",
        s.time_s, s.device_mm.x(), s.device_mm.y(), s.device_mm.z(), q.w(), q.x(), q.y(), q.z(),
        s.proxy_mm.x(), s.proxy_mm.y(), s.proxy_mm.z(), s.force_n.x(), s.force_n.y(), s.force_n.z(),
        s.organs_touched, s.pericardium_force_n);
    out += line;
  }
  out += "# event t_s organ (0 bone, 1 pericardium, 2 lung) begins (1) or ends (0)\n";
  for (const SessionEvent& e : r.events) {
    std::snprintf(line, sizeof(line), "event %.17g %d %d\n", e.time_s, e.organ, e.begins ? 1 : 0);
    out += line;
  }
  return out;
}

SessionRecord ParseSessionRecord(const std::string& text, const std::string& source) {
  SessionRecord r;
  std::istringstream in(text);
  std::string line;
  int number = 0;
  bool have_period = false;
  while (std::getline(in, line)) {
    ++number;
    if (line.empty() || line[0] == '#') continue;
    std::istringstream f(line);
    std::string key;
    f >> key;
    bool ok = true;
    if (key == "patient") {
      ok = static_cast<bool>(f >> r.patient);
    } else if (key == "introducer") {
      ok = static_cast<bool>(f >> r.introducer);
    } else if (key == "period_s") {
      ok = static_cast<bool>(f >> r.period_s) && r.period_s > 0;
      have_period = ok;
    } else if (key == "tick") {
      SessionSample s;
      double q[4];
      ok = static_cast<bool>(f >> s.time_s >> s.device_mm.x() >> s.device_mm.y() >> s.device_mm.z() >> q[0] >>
                             q[1] >> q[2] >> q[3] >> s.proxy_mm.x() >> s.proxy_mm.y() >> s.proxy_mm.z() >>
                             s.force_n.x() >> s.force_n.y() >> s.force_n.z() >> s.organs_touched >>
                             s.pericardium_force_n);
      s.orientation = Eigen::Quaterniond(q[0], q[1], q[2], q[3]);
      if (ok) r.samples.push_back(s);
    } else if (key == "event") {
      SessionEvent e;
      int begins = 0;
      ok = static_cast<bool>(f >> e.time_s >> e.organ >> begins) && e.organ >= 0 && e.organ < kNumOrgans;
      e.begins = begins != 0;
      if (ok) r.events.push_back(e);
    } else {
      ThrowBadInput(source, "unknown line '" + key + "'", number);
    }
    if (!ok) ThrowBadInput(source, "a malformed '" + key + "' line", number);
  }
  if (!have_period || r.introducer.empty()) ThrowBadInput(source, "no 'period_s' or 'introducer' line");
  IntroducerNamed(r.introducer);
  return r;
}

void WriteSessionRecord(const std::filesystem::path& path, const SessionRecord& record) {
  WriteFileAtomically(path, FormatSessionRecord(record));
}

SessionRecord ReadSessionRecord(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) ThrowBadInput(path.string(), "cannot open the session record");
  std::ostringstream text;
  text << in.rdbuf();
  return ParseSessionRecord(text.str(), path.string());
}

}  // namespace pectus::trainer
