// pectus: one joint adjustment of the rigid poses of all sweeps from point-to-plane correspondences
// between every overlapping pair (a Ceres problem over all poses at once), so that alignment errors do
// not pile up around a loop of sweeps.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "shape/core/geometry.h"
#include "shape/surface/sweep_surface.h"

namespace pectus {

/// Options of AdjustPoses.
struct PoseAdjustmentOptions {
  std::size_t anchor = 0;             ///< the sweep whose pose is held (fixes the common frame)
  double min_robust_scale_mm = 0.02;  ///< floor of the Cauchy scale taken from the residuals' MAD (mm)
  int max_iterations = 30;            ///< Levenberg-Marquardt iterations at most

  /// False, with the reason in `why`, if a value is out of range.
  bool IsValid(std::string* why) const;
};

/// What AdjustPoses did.
struct PoseAdjustmentResult {
  double rms_before_mm = 0.0;    ///< RMS point-to-plane residual of all correspondences at the start
  double rms_after_mm = 0.0;     ///< the same at the end
  double robust_scale_mm = 0.0;  ///< sigma of the Cauchy loss (1.4826 MAD of the starting residuals)
  int iterations = 0;
  bool converged = false;  ///< Ceres stopped on a tolerance, not on max_iterations
  std::string message;     ///< Ceres' one-line report
};

/// Minimises sum rho((R_i n) . (T_j p - T_i q)) over the poses T_world_sweep of all sweeps but the
/// anchor (Chen and Medioni 1992 point-to-plane residuals, Cauchy loss rho of scale 2.3849 sigma), with
/// each rotation a unit quaternion on its manifold. Solved with sparse normal Cholesky: every residual
/// touches two poses.
/// @param[in]     pairs          correspondences; the sweep indices must be < T_world_sweep->size()
/// @param[in,out] T_world_sweep  poses, best centred on the data (rotations act about the origin)
PoseAdjustmentResult AdjustPoses(const std::vector<SweepCorrespondence>& pairs,
                                 std::vector<Rigid3>* T_world_sweep,
                                 const PoseAdjustmentOptions& options = {});

}  // namespace pectus
