// pectus: align the overlapping sweeps of a hand-held scan and merge them into one cloud.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "registration/icp.h"
#include "shape/core/geometry.h"
#include "shape/core/timings.h"
#include "shape/surface/sweep_surface.h"

namespace pectus {

/// Options of MergeSweeps. Distances in mm; the defaults suit laser sweeps with ~0.5-1 mm spacing.
struct SweepMergeOptions {
  // --- Alignment ---
  bool refine_poses = true;     ///< false: keep the given poses, only merge
  std::size_t anchor = 0;       ///< the sweep whose pose is kept (fixes the common frame)
  SweepSurfaceOptions surface;  ///< normals, border points and subsample of each sweep
  /// Two sweeps overlap where a sample of one has a point of the other this close at the starting
  /// poses, on the same side (normals within 45 degrees) and away from the other's border.
  double overlap_distance_mm = 5.0;
  double min_overlap_fraction = 0.1;  ///< pairs overlapping less (of the smaller sweep) are not linked
  /// Pairwise point-to-plane ICP (robust, gated, coarse to fine); its target is the other sweep without
  /// its border points.
  IcpOptions pairwise = [] {
    IcpOptions o;
    o.auto_level_points = {1000, 4000};
    o.max_normal_angle_deg = 45.0;
    o.target_pose_sd_fraction = 0.0;  // a start for the joint solve below, which uses every pair again
    return o;
  }();
  int global_rounds = 8;              ///< at most this many rounds of correspondence search + joint solve
  int global_points_per_pair = 3000;  ///< source samples per linked pair, direction and round
  /// Gate of the joint solve (mm); 0 = 3 times the median point spacing of the sweeps.
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
};

/// Overlap between two linked sweeps, before and after alignment.
struct SweepPairReport {
  std::size_t i = 0, j = 0;       ///< sweep indices, i < j
  double overlap_fraction = 0.0;  ///< of the smaller sweep's samples
  double rms_before_mm = 0.0;     ///< RMS point-to-plane distance of correspondences at the start
  double rms_after_mm = 0.0;      ///< the same at the final poses
  double median_after_mm = 0.0;   ///< median nearest-point distance at the final poses
  bool pairwise_success = false;  ///< the pairwise ICP passed its acceptance tests
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
  PointCloud merged;                  ///< world frame; normals; scalar "sweep" = source sweep index
  std::int64_t points_in = 0;
  std::int64_t outliers_removed = 0;
  std::int64_t points_out = 0;
  /// Wall time (s): "normals", "overlap", "pairwise_icp", "global_adjustment", "blend", "filter".
  Timings timings_s;
  std::string message;  ///< one line on what happened

  /// One line for a log: the message, the joint solve's RMS before and after, and the wall time.
  std::string BriefReport() const;
};

/// Aligns and merges sweeps: orients every sweep's normals to one side, finds the overlapping pairs,
/// aligns each pair by point-to-plane ICP (Chen and Medioni 1992), starts every pose from a maximum
/// spanning tree of the pairs, then adjusts all poses jointly (AdjustPoses) so that errors do not pile up
/// around a loop; blends overlaps, removes outliers, decimates. Deterministic for any number of threads.
/// @param[in] sweeps               each sweep in its own (scanner) frame, mm; normals are estimated here
/// @param[in] T_world_sweep_start  starting pose of each sweep (from the scanner, a .conf, or identity)
/// @param[in] options              see SweepMergeOptions
/// Throws Error(kUsage) for invalid options, Error(kBadInput) for fewer than one sweep, a sweep with
/// fewer than 10 points or a size mismatch, and Error(kFailure) if a sweep overlaps no other sweep.
SweepMergeResult MergeSweeps(const std::vector<PointCloud>& sweeps,
                             const std::vector<Rigid3>& T_world_sweep_start,
                             const SweepMergeOptions& options = {});

}  // namespace pectus
