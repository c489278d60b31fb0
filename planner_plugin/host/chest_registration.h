// pectus planner host: the predicted chest registered to the average chest by landmarks (dissertation
// §4.3.1: sternal notch, centre of the manubrium and xiphoid). Those three lie on the midline, so they
// leave the roll about the sternal line free; the chests' anterior directions fix it.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "shape/core/geometry.h"
#include "shape/core/landmarks.h"

namespace pectus::planner {

/// How the chests are registered.
struct ChestRegistrationOptions {
  /// Similarity (scale too, for a patient smaller or larger than the average chest; default) or rigid.
  bool similarity = true;
  /// Landmarks used where both sets have them; "sternal_notch" and "xiphoid" are required.
  std::vector<std::string> labels = {"sternal_notch", "manubrium_centre", "xiphoid"};
  bool IsValid(std::string* why) const;
};

/// A registration.
struct ChestRegistrationResult {
  Similarity3 T_target_source;    ///< x_target = T * x_source
  std::vector<std::string> used;  ///< landmark labels used
  double landmark_rms_mm = 0;     ///< RMS distance of the used landmarks after registration
};

/// The area-weighted mean of the face normals of `mesh` (unit): for a chest surface with outward faces,
/// its anterior direction. Throws Error(kBadInput) naming `what` for a mesh without area.
Eigen::Vector3d AnteriorDirection(const TriangleMesh& mesh, const std::string& what);

/// Registers `source` to `target`: the rotation takes the source frame (sternal axis notch to xiphoid,
/// anterior direction made orthogonal to it) onto the target's; then scale (if similarity) and translation
/// are the least-squares fit of the used landmarks (closed form). Throws Error(kBadInput) naming the set
/// without a required landmark, or whose anterior direction is parallel to its sternal axis.
ChestRegistrationResult RegisterChestByLandmarks(const LandmarkSet& source,
                                                 const Eigen::Vector3d& source_anterior,
                                                 const LandmarkSet& target,
                                                 const Eigen::Vector3d& target_anterior,
                                                 const ChestRegistrationOptions& options = {});

}  // namespace pectus::planner
