// pectus trainer: the scores of a session (docs/trainer.md, "Scores"): each a documented definition over
// the recorded ticks, so a replayed record scores the same bit for bit.
#pragma once

#include <string>

#include "planner_plugin/trainer/trainer_scene.h"
#include "planner_plugin/trainer/trainer_session.h"

namespace pectus::trainer {

/// The penalties of the overall score (points off 100).
struct SessionScoreOptions {
  double near_pericardium_mm = 5.0;      ///< "near the pericardium": the tip within this, mm
  double contact_points = 30.0;          ///< for touching the pericardium at all
  double extra_contact_points = 5.0;     ///< for each further contact
  double shortfall_points_per_mm = 3.0;  ///< per mm the nearest approach falls short of near_pericardium_mm
  double near_points_per_s = 2.0;        ///< per second near the pericardium
  double wrong_space_points = 15.0;      ///< for an entry or exit through another space than planned
  double deviation_points_per_mm = 1.0;  ///< per mm of RMS deviation from the planned tunnel
  bool IsValid(std::string* why) const;
};

/// What a session scored. Lengths in mm, times in s, forces in N.
struct SessionScore {
  double min_pericardium_distance_mm = 0;  ///< the tip's nearest approach to the pericardium
  double time_near_pericardium_s = 0;   ///< ticks with the tip within near_pericardium_mm, times the period
  int pericardial_contacts = 0;         ///< times the tip or the shaft began touching the pericardium
  double peak_pericardium_force_n = 0;  ///< the largest force the pericardium took
  double peak_force_n = 0;              ///< the largest force sent to the device
  double path_length_mm = 0;            ///< the tip's (proxy's) path
  /// RMS of the tip's distance to the planned tunnel over the ticks whose tip lies beside it (its nearest
  /// point not an end of the tunnel beyond which the tip is: outside the ports it is not counted)
  double rms_tunnel_deviation_mm = 0;
  IntercostalSpace entry, exit;  ///< the spaces the tip passed through (nearest the planned ports)
  bool entry_as_planned = false, exit_as_planned = false;
  double total_time_s = 0;  ///< first to last tick
  double score = 0;         ///< 100 minus the penalties, at least 0
  std::string BriefReport() const;
};

/// Scores `record` in `scene`. Throws Error(kBadInput) for a record of fewer than two ticks.
SessionScore ScoreSession(const TrainerScene& scene, const SessionRecord& record,
                          const SessionScoreOptions& options = {});

}  // namespace pectus::trainer
