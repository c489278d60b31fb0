// pectus: one Gauss-Newton step of the joint adjustment of all sweeps' poses, each held to its tracker
// pose with the tracker's accuracy, in which every overlapping pair corrects only the directions its
// overlap pins (issue 13; docs/reconstruction.md, "The tracker as a prior").
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <string>
#include <vector>

#include "shape/core/geometry.h"
#include "shape/surface/sweep_surface.h"

namespace pectus {

/// The tracker's word on every sweep's pose: where it put the sweep, and how far that can be trusted
/// (one standard deviation of its stated accuracy).
struct PosePrior {
  std::vector<Rigid3> T_world_sweep;    ///< the tracker's pose of every sweep (same frame as the poses)
  std::vector<Eigen::Vector3d> centre;  ///< per sweep, its centroid (sweep frame, mm), where
                                        ///< translation_sd_mm bounds the tracker's error
  double rotation_sd_deg = 0.5;         ///< rotation error, 1 sd per axis (degrees), > 0
  double translation_sd_mm = 2.3;       ///< position error at `centre`, 1 sd per axis (mm), > 0
};

/// Options of AdjustPosesToTracker.
struct TrackerAdjustmentOptions {
  double min_robust_scale_mm = 0.02;  ///< floor of the Cauchy scale taken from the residuals' MAD (mm)
  /// A direction of a pair's relative pose is pinned when the overlap's information along it is at least
  /// this many times what the noise of the normals alone would put there (a generalised eigenvalue
  /// lambda); it then counts with lambda - 1, the spurious part taken off. 4 keeps the plane's and the
  /// cylinder's free directions free (lambda about 1 there) and lets weakly pinned ones count: on the
  /// issue-13 chest grid 4 loses less to a 4 mm tracker error than 25 (shape 0.14-0.31 against
  /// 0.20-0.40 mm RMS) at 0.03-0.09 against 0.02-0.08 mm from exact poses (docs/benchmarks/merge.md).
  double min_pinned_ratio = 4.0;
  /// Count each point's noise once, however many correspondences of a pair use it: a point of the overlap
  /// is the source of one correspondence and the target of about one more (the other direction, or a
  /// neighbour's nearest point), and both residuals carry its noise with the same sign on the pair's
  /// relative pose. The pair's information is scaled by sum_k 2 w_k^2 / sum_points (sum_{k using it}
  /// w_k)^2 (w_k the correspondence's robust weight): 1 when no point is shared, 1/2 when every point
  /// of the overlap is used once from each side (the two sides then hold what one holds). It makes the
  /// joint step's information honest (the merge's shape over its model's prediction 1.59 -> 1.33 on the
  /// issue-13 grid's 4 mm, 15 % cells) but not the merge better (seed 1: the line met in 16 cells of 36
  /// against 15, seed 2: 11 against 11; docs/benchmarks/merge.md): off, every residual independent.
  /// Needs the rows (SweepCorrespondence::p_row, q_row).
  bool count_shared_points = false;

  /// False, with the reason in `why`, if a value is out of range.
  bool IsValid(std::string* why) const;
};

/// What the overlap of one pair said, and what the step did.
struct PairConstraintReport {
  std::size_t i = 0, j = 0;   ///< the sweeps
  int pinned_directions = 0;  ///< of the six of their relative pose
  int correspondences = 0;    ///< used (both directions)
  /// The factor on the pair's information for points its correspondences share (count_shared_points;
  /// 1: none shared or not counted).
  double independent_fraction = 1.0;
};

/// What AdjustPosesToTracker did.
struct TrackerAdjustmentResult {
  double rms_before_mm = 0.0;    ///< RMS point-to-plane residual of the correspondences at the start
  double robust_scale_mm = 0.0;  ///< sigma of the Cauchy loss (1.4826 MAD of the residuals)
  std::vector<PairConstraintReport> pairs;
  /// The joint normal matrix of the step (6n x 6n, the pairs' pinned parts and the priors; per sweep a
  /// twist (rotation rad, translation mm) about the world origin): the information the step had on the
  /// poses, whose inverse is their covariance under the model.
  Eigen::MatrixXd information;
};

/// One Gauss-Newton step of min sum_pairs rho(r / s) + sum_sweeps |e_s|^2 over all poses, r the
/// point-to-plane residuals (R_i n).(T_j p - T_i q) (Chen and Medioni 1992), s their robust scale and
/// e_s = (rotation vector of R_s R_s0^T / sd_rad, (T_s c_s - T_s0 c_s) / sd_mm) sweep s's departure from
/// the tracker. Each pair's residuals are first reduced to a 6 x 6 constraint on its relative motion
/// (a twist about the pair's overlap centre); its eigen-directions (generalised, against the information
/// the normals' noise alone would give) that the overlap does not pin are dropped, so that a strip
/// sliding along a smooth surface is not pushed by the noise of its normals and stays where the tracker
/// put it (degeneracy-aware solution remapping, Zhang, Kaess and Singh 2016). The joint step is one dense
/// 6n x 6n solve (LDL^T); the priors make it definite.
/// @param[in]     pairs          correspondences, grouped by the pair (c.i, c.j) they belong to
/// @param[in]     sweeps         the sweeps, for their normals' expected noise (normal_variance)
/// @param[in]     prior          the tracker's poses and accuracy, one per pose
/// @param[in,out] T_world_sweep  poses, best centred on the data
TrackerAdjustmentResult AdjustPosesToTracker(const std::vector<SweepCorrespondence>& pairs,
                                             const std::vector<SweepSurface>& sweeps, const PosePrior& prior,
                                             std::vector<Rigid3>* T_world_sweep,
                                             const TrackerAdjustmentOptions& options = {});

}  // namespace pectus
