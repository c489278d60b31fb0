#include "planner_plugin/trainer/session_score.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include "shape/core/error.h"

namespace pectus::trainer {

bool SessionScoreOptions::IsValid(std::string* why) const {
  const bool ok = near_pericardium_mm > 0 && contact_points >= 0 && extra_contact_points >= 0 &&
                  shortfall_points_per_mm >= 0 && near_points_per_s >= 0 && wrong_space_points >= 0 &&
                  deviation_points_per_mm >= 0;
  if (!ok && why != nullptr) *why = "session score: the distance must be > 0 and every penalty >= 0";
  return ok;
}

std::string SessionScore::BriefReport() const {
  char text[400];
  std::snprintf(
      text, sizeof(text),
      "score %.1f: pericardium %.2f mm at nearest, %.2f s within reach, %d contacts (peak %.2f N); path "
      "%.0f mm, %.2f mm RMS off the tunnel; entry %s%s, exit %s%s; %.1f s",
      score, min_pericardium_distance_mm, time_near_pericardium_s, pericardial_contacts,
      peak_pericardium_force_n, path_length_mm, rms_tunnel_deviation_mm, entry.Name().c_str(),
      entry_as_planned ? "" : " (planned other)", exit.Name().c_str(),
      exit_as_planned ? "" : " (planned other)", total_time_s);
  return text;
}

SessionScore ScoreSession(const TrainerScene& scene, const SessionRecord& record,
                          const SessionScoreOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) ThrowUsage(why);
  if (record.samples.size() < 2) ThrowBadInput("session record", "fewer than two ticks");
  SessionScore s;
  s.min_pericardium_distance_mm = std::numeric_limits<double>::infinity();
  double sum_sq = 0;
  std::size_t inside = 0;
  double nearest_entry = std::numeric_limits<double>::infinity(), nearest_exit = nearest_entry;
  Eigen::Vector3d at_entry = record.samples.front().proxy_mm, at_exit = record.samples.back().proxy_mm;
  bool touching = false;
  for (std::size_t i = 0; i < record.samples.size(); ++i) {
    const SessionSample& t = record.samples[i];
    const double d = scene.DistanceToPericardium(t.proxy_mm);
    s.min_pericardium_distance_mm = std::min(s.min_pericardium_distance_mm, d);
    if (d < options.near_pericardium_mm) s.time_near_pericardium_s += record.period_s;
    const bool now = (t.organs_touched >> kPericardium & 1u) != 0;
    if (now && !touching) ++s.pericardial_contacts;
    touching = now;
    s.peak_pericardium_force_n = std::max(s.peak_pericardium_force_n, t.pericardium_force_n);
    s.peak_force_n = std::max(s.peak_force_n, t.force_n.norm());
    if (i > 0) s.path_length_mm += (t.proxy_mm - record.samples[i - 1].proxy_mm).norm();
    bool outside = false;
    const double dev = DistanceToPolyline(scene.tunnel.points, t.proxy_mm, &outside);
    if (!outside) sum_sq += dev * dev, ++inside;
    const double to_entry = (t.proxy_mm - scene.tunnel.entry_port).norm();
    const double to_exit = (t.proxy_mm - scene.tunnel.exit_port).norm();
    if (t.proxy_mm.x() < 0 && to_entry < nearest_entry) nearest_entry = to_entry, at_entry = t.proxy_mm;
    if (t.proxy_mm.x() > 0 && to_exit < nearest_exit) nearest_exit = to_exit, at_exit = t.proxy_mm;
  }
  s.rms_tunnel_deviation_mm = inside > 0 ? std::sqrt(sum_sq / static_cast<double>(inside)) : 0.0;
  s.entry = scene.SpaceAt(at_entry);
  s.exit = scene.SpaceAt(at_exit);
  s.entry_as_planned = s.entry == scene.tunnel.entry;
  s.exit_as_planned = s.exit == scene.tunnel.exit;
  s.total_time_s = record.samples.back().time_s - record.samples.front().time_s;
  double penalty = 0;
  if (s.pericardial_contacts > 0) {
    penalty += options.contact_points + options.extra_contact_points * (s.pericardial_contacts - 1);
  }
  penalty += options.shortfall_points_per_mm *
             std::max(0.0, options.near_pericardium_mm - s.min_pericardium_distance_mm);
  penalty += options.near_points_per_s * s.time_near_pericardium_s;
  if (!s.entry_as_planned) penalty += options.wrong_space_points;
  if (!s.exit_as_planned) penalty += options.wrong_space_points;
  penalty += options.deviation_points_per_mm * s.rms_tunnel_deviation_mm;
  s.score = std::max(0.0, 100.0 - penalty);
  return s;
}

}  // namespace pectus::trainer
