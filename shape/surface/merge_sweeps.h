// pectus: align the overlapping sweeps of a hand-held scan and merge them into one cloud.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "registration/icp.h"
#include "shape/core/geometry.h"
#include "shape/core/timings.h"
#include "shape/surface/adjust_poses_to_tracker.h"
#include "shape/surface/sweep_surface.h"

namespace pectus {

/// Options of MergeSweeps. Distances in mm; the defaults suit laser sweeps with ~0.5-1 mm spacing.
struct SweepMergeOptions {
  // --- Alignment ---
  bool refine_poses = true;     ///< false: keep the given poses, only merge
  std::size_t anchor = 0;       ///< without a tracker prior, the sweep whose pose is kept
  SweepSurfaceOptions surface;  ///< normals, border points and subsample of each sweep
  /// The tracker's stated accuracy, one standard deviation per axis: the rotation of each sweep's pose
  /// (degrees), which turns it about the tracker's origin `tracker_lever_mm` away, and its translation
  /// (mm). Every sweep's starting pose is carried into the joint adjustment as a prior with this spread
  /// (PosePrior): what the overlaps pin follows the data, what they leave free (a smooth strip sliding
  /// along the chest) stays where the tracker put it, and given exact poses nothing moves by more than
  /// the noise allows. The defaults are an electromagnetic tracker's (Polhemus FastScan class; 2.3 mm at
  /// the skin). Both 0: no prior; pairwise ICP from the starting poses, then the joint adjustment with the
  /// anchor held (for starting poses of unknown accuracy, e.g. a .conf of a rough manual alignment).
  double tracker_deg = 0.5;
  double tracker_mm = 1.5;
  double tracker_lever_mm = 200.0;  ///< distance from the tracker's origin to the skin (mm)
  /// The tracker's readings (world from sweep), one per sweep, when the merge starts elsewhere (a
  /// previous merge, a diagnostic start at the truth); empty: the starting poses are the readings.
  std::vector<Rigid3> tracker_poses;
  /// Two sweeps overlap where a sample of one lies this close to the surface of the other (same side,
  /// normals within 45 degrees, not beyond its edge). 0: three standard deviations of two sweeps'
  /// relative tracker error at the skin (3 sqrt(2) hypot(tracker_mm, tracker_deg lever), 9.8 mm by
  /// default; 5 mm without a prior). The joint adjustment's gate starts there and halves every round down
  /// to global_max_distance_mm, so the capture is wide and the end is at the noise.
  double overlap_distance_mm = 0.0;
  /// Pairs sharing less than this fraction of the smaller sweep's area are not linked.
  double min_overlap_fraction = 0.05;
  /// Pairwise point-to-plane ICP (robust, gated, coarse to fine), without a tracker prior only; its
  /// target is the other sweep without its border points.
  IcpOptions pairwise = [] {
    IcpOptions o;
    o.auto_level_points = {1000, 4000};
    o.max_normal_angle_deg = 45.0;
    o.target_pose_sd_fraction = 0.0;  // a start for the joint solve below, which uses every pair again
    return o;
  }();
  TrackerAdjustmentOptions tracker_adjustment;  ///< each round's joint step, with a tracker prior
  /// With a tracker prior: after the rounds at tracker_adjustment.min_pinned_ratio (4) and the fit of the
  /// tracker's accuracy below, the rounds are run once more with this pinned ratio, from where the poses
  /// are and with the fitted prior: 2, every direction whose information is at least twice the normals'
  /// noise counts (with lambda - 1). A tracker error of millimetres is then corrected along the weakly
  /// pinned directions too, while the fitted prior still holds the weak directions of exact poses. 1 would
  /// let a plane strip slide on its normals' noise (lambda scatters about 1 along a free direction).
  /// tracker_adjustment.min_pinned_ratio or more: no final rounds (docs/benchmarks/merge.md).
  double final_min_pinned_ratio = 2.0;
  /// With final rounds: their correspondences come from every point of each overlap (each point of the
  /// source within twice the finest gate of the target at the start of the final rounds), not from the
  /// subsample and not capped by global_points_per_pair: the information the weakly pinned directions
  /// get grows about fourfold (sample_spacings 2 keeps a quarter of the points), the cost about twofold.
  bool final_every_point = true;
  /// With a tracker prior: after the rounds, estimate how far off the stated accuracy the tracker really
  /// was from the corrections along the directions the overlaps pin (empirical Bayes: their squares, less
  /// the share the data's own noise puts there by the joint step's information, per pinned direction),
  /// scale the prior by that factor (0.01 to 3 in all) and adjust again from there (up to six times,
  /// while the factor is off 1 by more than 25 %), so that what the overlaps pin only weakly is held as
  /// tightly as the tracker proved to be: given exact poses, the weak directions no longer follow the
  /// data's noise.
  bool fit_tracker_accuracy = true;
  int global_rounds = 10;             ///< at most this many rounds of correspondence search + joint solve
  int global_points_per_pair = 3000;  ///< source samples per linked pair, direction and round
  /// Finest gate of the joint solve (mm); 0 = 3 times the median point spacing of the sweeps.
  double global_max_distance_mm = 0.0;

  // --- Merging ---
  /// Blending radius (mm): each point moves along its normal to the weighted mean surface of all sweeps
  /// within this radius (Gaussian weights, sigma = radius / 2). 0 = no blending. Small keeps detail; large
  /// joins sweeps that are not perfectly aligned.
  double smoothing_mm = 0.0;
  int outlier_neighbours = 16;     ///< statistical outlier removal: k nearest neighbours (0 = off)
  double outlier_std_ratio = 3.0;  ///< drop points whose mean kNN distance > mean + ratio * std
  double target_spacing_mm = 0.0;  ///< voxel decimation to this spacing; 0 = keep every point

  /// False, with the reason in `why`, if a value is out of range.
  bool IsValid(std::string* why) const;
  /// True when tracker_deg or tracker_mm is > 0.
  bool HasTrackerPrior() const;
  /// overlap_distance_mm, or the radius it stands for when 0 (mm).
  double StartingRadiusMm() const;
};

/// Overlap between two linked sweeps, before and after alignment.
struct SweepPairReport {
  std::size_t i = 0, j = 0;       ///< sweep indices, i < j
  double overlap_fraction = 0.0;  ///< of the smaller sweep's samples, at the final poses
  double rms_before_mm = 0.0;     ///< RMS point-to-plane distance of correspondences at the start
  double rms_after_mm = 0.0;      ///< the same at the final poses
  double median_after_mm = 0.0;   ///< median nearest-point distance at the final poses
  bool pairwise_success = false;  ///< the pairwise ICP passed its acceptance tests (false if not run)
  int pinned_directions = -1;     ///< with a tracker prior: of the six of the pair's relative pose, how
                                  ///< many its overlap pinned in the last round (-1: no prior)
};

/// What MergeSweeps did.
struct SweepMergeResult {
  std::vector<Rigid3> T_world_sweep;   ///< final pose of each sweep (x_world = T x_sweep, mm)
  std::vector<double> correction_deg;  ///< rotation of each sweep's correction T_final T_initial^-1
  std::vector<double> correction_mm;   ///< translation of the correction at the sweep's centroid (mm)
  std::vector<SweepPairReport> pairs;
  double global_rms_before_mm = 0.0;  ///< RMS residual of the last joint solve's correspondences, before
  double global_rms_after_mm = 0.0;   ///< and after it
  int global_rounds = 0;              ///< rounds of the joint solve run
  /// With a tracker prior and fit_tracker_accuracy: the factor the stated accuracy was scaled by (0: not
  /// fitted).
  double tracker_accuracy_factor = 0.0;
  PointCloud merged;  ///< world frame; normals; scalar "sweep" = source sweep index
  std::int64_t points_in = 0;
  std::int64_t outliers_removed = 0;
  std::int64_t points_out = 0;
  /// Wall time (s): "normals", "overlap", "pairwise_icp", "global_adjustment", "blend", "filter".
  Timings timings_s;
  std::string message;  ///< one line on what happened

  /// One line for a log: the message, the joint solve's RMS before and after, and the wall time.
  std::string BriefReport() const;
};

/// Aligns and merges sweeps: orients every sweep's normals to one side, finds the overlapping pairs on
/// their geometry, and adjusts all poses jointly (AdjustPoses: point-to-plane residuals of every linked
/// pair, Chen and Medioni 1992) from a wide gate down to the noise, each sweep held to its tracker pose
/// with the tracker's accuracy, so that errors neither pile up around a loop nor slide a sweep along a
/// direction its overlaps do not pin. Without a tracker prior, every linked pair is first aligned by ICP
/// and the poses start from a maximum spanning tree of the pairs. Then blends overlaps, removes
/// outliers, decimates. Deterministic for any number of threads.
/// @param[in] sweeps               each sweep in its own (scanner) frame, mm; normals are estimated here
/// @param[in] T_world_sweep_start  starting pose of each sweep (from the scanner, a .conf, or identity)
/// @param[in] options              see SweepMergeOptions
/// @param[in] names                each sweep's name for messages (e.g. its file); empty: "sweep N"
/// Throws Error(kUsage) for invalid options, Error(kBadInput) for fewer than one sweep, a sweep with
/// fewer than 10 points or a size mismatch, and Error(kFailure) naming a sweep that overlaps no other
/// sweep, with its distance to the nearest one.
SweepMergeResult MergeSweeps(const std::vector<PointCloud>& sweeps,
                             const std::vector<Rigid3>& T_world_sweep_start,
                             const SweepMergeOptions& options = {},
                             const std::vector<std::string>& names = {});

}  // namespace pectus
