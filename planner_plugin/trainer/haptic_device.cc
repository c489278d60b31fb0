#include "planner_plugin/trainer/haptic_device.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

#include "shape/core/atomic_file.h"
#include "shape/core/error.h"

namespace pectus::trainer {

DeviceState Trajectory::At(double time_s) const noexcept {
  if (samples.empty()) return {};
  if (time_s <= samples.front().time_s) return samples.front();
  if (time_s >= samples.back().time_s) return samples.back();
  const auto it = std::upper_bound(samples.begin(), samples.end(), time_s,
                                   [](double t, const DeviceState& s) { return t < s.time_s; });
  const DeviceState& b = *it;
  const DeviceState& a = *(it - 1);
  if (time_s == a.time_s) return a;
  const double w = (time_s - a.time_s) / (b.time_s - a.time_s);
  DeviceState s;
  s.time_s = time_s;
  s.position_mm = a.position_mm + w * (b.position_mm - a.position_mm);
  s.velocity_mm_s = a.velocity_mm_s + w * (b.velocity_mm_s - a.velocity_mm_s);
  s.orientation = a.orientation.slerp(w, b.orientation);
  s.buttons = a.buttons;
  return s;
}

Trajectory ParseTrajectory(const std::string& text, const std::string& source) {
  Trajectory out;
  std::istringstream in(text);
  std::string line;
  int number = 0;
  while (std::getline(in, line)) {
    ++number;
    const auto first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos || line[first] == '#') continue;
    std::istringstream fields(line);
    DeviceState s;
    double q[4];
    long long buttons = 0;
    if (!(fields >> s.time_s >> s.position_mm.x() >> s.position_mm.y() >> s.position_mm.z() >> q[0] >> q[1] >>
          q[2] >> q[3] >> buttons)) {
      ThrowBadInput(source, "expected 't_s x_mm y_mm z_mm qw qx qy qz buttons'", number);
    }
    std::string rest;
    if (fields >> rest) ThrowBadInput(source, "unexpected '" + rest + "' after the 9 fields", number);
    const Eigen::Quaterniond quat(q[0], q[1], q[2], q[3]);
    if (!std::isfinite(s.time_s) || !s.position_mm.allFinite() || !quat.coeffs().allFinite() ||
        std::abs(quat.norm() - 1) > 1e-6) {
      ThrowBadInput(source, "non-finite value, or a quaternion not of unit length", number);
    }
    if (buttons < 0 || buttons > 0xffffffffLL) ThrowBadInput(source, "buttons must be a 32-bit mask", number);
    if (!out.samples.empty() && !(s.time_s > out.samples.back().time_s)) {
      ThrowBadInput(source, "times must increase", number);
    }
    s.orientation = quat;
    s.buttons = static_cast<std::uint32_t>(buttons);
    out.samples.push_back(s);
  }
  if (out.samples.empty()) ThrowBadInput(source, "no samples");
  // Velocities: central differences (one-sided at the ends).
  const std::size_t n = out.samples.size();
  for (std::size_t i = 0; i < n && n > 1; ++i) {
    const DeviceState& a = out.samples[i == 0 ? 0 : i - 1];
    const DeviceState& b = out.samples[i + 1 == n ? n - 1 : i + 1];
    out.samples[i].velocity_mm_s = (b.position_mm - a.position_mm) / (b.time_s - a.time_s);
  }
  return out;
}

Trajectory ReadTrajectory(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) ThrowBadInput(path.string(), "cannot open the trajectory file");
  std::ostringstream text;
  text << in.rdbuf();
  return ParseTrajectory(text.str(), path.string());
}

std::string FormatTrajectory(const Trajectory& trajectory) {
  std::string out = "# pectus trainer trajectory: t_s x_mm y_mm z_mm qw qx qy qz buttons\n";
  char line[400];
  for (const DeviceState& s : trajectory.samples) {
    const Eigen::Quaterniond& q = s.orientation;
    std::snprintf(line, sizeof(line), "%.17g %.17g %.17g %.17g %.17g %.17g %.17g %.17g %u\n", s.time_s,
                  s.position_mm.x(), s.position_mm.y(), s.position_mm.z(), q.w(), q.x(), q.y(), q.z(),
                  s.buttons);
    out += line;
  }
  return out;
}

void WriteTrajectory(const std::filesystem::path& path, const Trajectory& trajectory) {
  WriteFileAtomically(path, FormatTrajectory(trajectory));
}

bool SimulatedHandOptions::IsValid(std::string* why) const {
  const bool ok = mass_kg > 0 && grip_n_per_mm > 0 && damping_n_s_per_mm >= 0 && step_s > 0 && step_s <= 0.01;
  if (!ok && why != nullptr)
    *why = "simulated hand: mass, grip and step must be > 0 (step <= 10 ms), damping >= 0";
  return ok;
}

SimulatedHand::SimulatedHand(Trajectory target, const SimulatedHandOptions& options)
    : target_(std::move(target)), options_(options) {
  std::string why;
  if (!options.IsValid(&why)) ThrowUsage(why);
  if (target_.samples.empty()) ThrowUsage("simulated hand: an empty target trajectory");
  time_s_ = target_.samples.front().time_s;
  x_mm_ = target_.samples.front().position_mm;
  v_mm_s_.setZero();
}

DeviceState SimulatedHand::Read(double time_s) noexcept {
  const double h = options_.step_s;
  // Whole steps up to time_s (a hair of slack so that k * h sums reach k * h).
  while (time_s_ + 0.5 * h <= time_s) {
    const DeviceState goal = target_.At(time_s_);
    const Eigen::Vector3d f_n = options_.grip_n_per_mm * (goal.position_mm - x_mm_) -
                                options_.damping_n_s_per_mm * v_mm_s_ + force_n_;
    v_mm_s_ += h * 1000.0 * f_n / options_.mass_kg;  // N / kg = m/s^2 = 1000 mm/s^2
    x_mm_ += h * v_mm_s_;
    time_s_ += h;
  }
  DeviceState s = target_.At(time_s_);
  s.time_s = time_s_;
  s.position_mm = x_mm_;
  s.velocity_mm_s = v_mm_s_;
  return s;
}

}  // namespace pectus::trainer
