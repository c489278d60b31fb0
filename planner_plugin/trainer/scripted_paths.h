// pectus trainer: scripted introducer paths through a scene, the targets a simulated hand follows in tests
// and benchmarks: an expert's along the planned tunnel (with a small wobble of the hand), and a novice's
// mistakes: too deep under the sternum, onto the pericardium, through the wrong intercostal space.
#pragma once

#include <string>

#include "planner_plugin/trainer/haptic_device.h"
#include "planner_plugin/trainer/trainer_scene.h"

namespace pectus::trainer {

enum class PathKind { kExpert, kTooDeep, kOntoPericardium, kWrongSpace };

/// "expert", "too deep", "onto the pericardium", "wrong space".
const char* PathKindName(PathKind kind);

struct ScriptedPathOptions {
  PathKind kind = PathKind::kExpert;
  double speed_mm_s = 40.0;       ///< along the path
  double wobble_mm = 1.0;         ///< amplitude of the hand's sideways wobble (two sines)
  double wobble_phase_rad = 0.0;  ///< makes one path of a set differ from another
  double outside_mm = 25.0;       ///< the path starts and ends this far outside the ports
  double sample_s = 0.01;         ///< the trajectory's sample spacing
  /// Over the middle of the tunnel, the too-deep path moves towards the pericardium until its nearest
  /// approach is `too_deep_clearance_mm` (default 2.5: within the 5 mm reach), and the one onto the
  /// pericardium until it aims `onto_pericardium_mm` into it (default 3), mm.
  double too_deep_clearance_mm = 2.5, onto_pericardium_mm = 3.0;
  bool IsValid(std::string* why) const;
};

/// The target trajectory: tip positions, and the introducer's axis along the path's direction (its
/// curved distal end leads; the shaft behind lies in the tunnel it has made). Throws Error(kUsage) for
/// invalid options, Error(kFailure) if the scene has no space above the planned one for kWrongSpace.
Trajectory MakeScriptedPath(const TrainerScene& scene, const ScriptedPathOptions& options);

}  // namespace pectus::trainer
