// pectus: fine rigid alignment of two surfaces sampled as points: point-to-plane ICP (Chen and Medioni
// 1992) or symmetric ICP (Rusinkiewicz 2019), robust, gated, coarse to fine.
#pragma once

#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "registration/estimate_normals.h"
#include "registration/kdtree.h"
#include "registration/robust_loss.h"
#include "shape/core/geometry.h"
#include "shape/core/timings.h"

namespace pectus {

/// The most target points IcpOptions::plane_points may take.
constexpr int kMaxPlanePoints = 4;

/// The error that ICP minimises.
enum class IcpMethod {
  kPointToPlane,  ///< sum w ((T p - q) . n_q)^2, target normals only
  kSymmetric,     ///< sum w ((T p - q) . (n_p + n_q))^2 with the rotation split between both sides
};

/// Parses "point-to-plane" or "symmetric"; throws Error(kUsage) otherwise.
IcpMethod ParseIcpMethod(const std::string& name);
std::string ToString(IcpMethod method);

/// One stage of coarse-to-fine ICP. The source sample of a level is `points` random source points when
/// points > 0, else one point per voxel of `voxel_size_mm` when that is > 0, else every source point.
struct IcpLevel {
  double voxel_size_mm = 0.0;    ///< source subsampling cube (mm); 0 = no voxel subsampling
  double max_distance_mm = 0.0;  ///< correspondences farther apart are dropped (mm), > 0
  int max_iterations = 30;       ///< iterations at this level, >= 1
  int points = 0;                ///< random sample of this many source points (RandomSample); 0 = off
};

/// The plane through several nearest target points (IcpOptions::plane_points, docs/registration.md): from
/// the nearest one's point `q` and normal `n`, the mean of the positions of `rows[0..count)` (nearest
/// first: rows[0] is the nearest, already in q and n) and the mean of their normals, each turned to agree
/// with `n`, normalised. Rows `take(row)` refuses are left out; with none taken q and n stay as they are.
template <class Take>
void PlaneThroughNearestPoints(const Points3& positions, const Points3& normals, const std::uint32_t* rows,
                               int count, Take take, Eigen::Vector3d* q, Eigen::Vector3d* n) {
  Eigen::Vector3d sum_q = *q, sum_n = *n;
  int used = 1;
  for (int h = 1; h < count; ++h) {
    if (!take(rows[h])) continue;
    const Eigen::Vector3d nh = normals.row(rows[h]).transpose();
    sum_q += positions.row(rows[h]).transpose();
    sum_n += nh.dot(*n) < 0.0 ? Eigen::Vector3d(-nh) : nh;
    ++used;
  }
  if (used > 1 && sum_n.squaredNorm() > 0.0) {
    *q = sum_q / used;
    *n = sum_n.normalized();
  }
}

/// Options of AlignIcp. The defaults suit hand-held body scans and laser sweeps in mm.
struct IcpOptions {
  IcpMethod method = IcpMethod::kPointToPlane;
  RobustLoss loss = RobustLoss::kCauchy;  ///< M-estimator of the residuals, scale from their MAD
  double min_robust_scale_mm = 0.02;      ///< floor of the MAD scale (mm), so exact data stay weighted
  /// Trimmed ICP (Chetverikov et al. 2002): drop this fraction of the correspondences with the largest
  /// residuals at every iteration; 0 keeps all (gating and the robust loss still apply). In [0, 0.9].
  double trim_fraction = 0.0;
  /// Drop a correspondence whose normals differ by more than this (degrees), when the source has
  /// normals; 0 = off. Ignores the normals' sign.
  double max_normal_angle_deg = 0.0;
  /// Drop a pair whose source point lies farther from its target point along the target's tangent plane
  /// than this many target point spacings: the source point is then over a hole in the target or beyond
  /// its edge, and the rim's plane would pull it (docs/registration.md). 0 = off.
  double max_tangential_spacings = 2.0;
  /// The target's plane at a source point: through the mean of its `plane_points` nearest target points
  /// (those within the gate), normal the mean of their normals (turned to agree with the nearest's). One
  /// noisy target point and its normal (a PCA of a dozen noisy neighbours) bias the pose: the nearest
  /// point is chosen for being near, noise included. The mean of four halves the target's share of the
  /// residual's noise (docs/registration.md, "The target's plane from its nearest points"). 1 = the nearest
  /// point's own plane (Chen and Medioni 1992). In [1, 4].
  int plane_points = 4;

  /// Coarse to fine. Empty = automatic: one level per entry of `auto_level_points`, a random sample of
  /// that many source points (nested: every level's sample contains the coarser ones; 0 or more than the
  /// source has = every point), the gate starting at `initial_max_distance_mm` and shrinking fourfold per
  /// level, down to `final_max_distance_mm`. The last level starts with 30000 points by default and
  /// grows while the sample costs accuracy (`target_pose_sd_fraction`); 0 = every point from the start.
  std::vector<IcpLevel> levels;
  std::vector<int> auto_level_points = {1000, 3000, 10000, 30000};  ///< source points per automatic level
  double initial_max_distance_mm = 20.0;  ///< gate of the first automatic level (mm)
  /// Smallest gate of the automatic levels (mm); 0 = 3 times the target's point spacing, right for two
  /// scans of one surface. Scans of different people differ by millimetres: use about 10 mm.
  double final_max_distance_mm = 0.0;
  int auto_max_iterations = 30;  ///< iterations per automatic level
  /// The last level's random sample grows (nested: every point used so far stays in) until what sampling
  /// adds to the pose's standard error, sd_n sqrt(1 - n/N) for n of the N source points, is at most this
  /// fraction of the residuals' robust scale (docs/registration.md, "Growing the last sample"); at the
  /// latest it takes every point. The pose's sd is the larger of the source centroid's and the rotation's
  /// times the RMS lever (mm). Applies when the last level is a random sample (points > 0). 0 = off: the
  /// sample keeps its size. In [0, 1).
  double target_pose_sd_fraction = 0.01;

  /// A level stops when an update rotates by less than this (degrees) and moves by less than
  /// `translation_tolerance_mm`, or when the pose is back where it was two iterations before (a cycle
  /// between correspondence sets); each level above the last uses ten times its finer neighbour's values.
  double rotation_tolerance_deg = 1e-3;
  double translation_tolerance_mm = 2e-3;
  /// When two successive updates point the same way, take the rest of their geometric series at once
  /// (Aitken extrapolation, docs/registration.md): the same fixed point in fewer iterations.
  bool extrapolate = true;

  /// Restrict the source to surface patches: points within `patch_radius_mm` of any of these centres
  /// (source frame, mm), as around landmarks. Empty = the whole source.
  std::vector<Eigen::Vector3d> patch_centres;
  double patch_radius_mm = 0.0;

  /// Acceptance. A result that misses any of these is returned with success = false and the reason.
  double max_rms_mm = 1.0;           ///< RMS point-to-plane distance of the inliers (mm)
  double min_inlier_fraction = 0.3;  ///< source points (finest level) with a target point within reach
  double inlier_distance_mm = 0.0;   ///< that reach (mm); 0 = the last level's gate
  double min_conditioning = 1e-5;    ///< smallest / largest eigenvalue of the scaled 6x6 normal matrix
  int min_correspondences = 30;      ///< fewer at any iteration is a failure

  /// False, with the reason in `why`, if a value is out of range.
  bool IsValid(std::string* why) const;
};

/// What happened at one level.
struct IcpLevelReport {
  double voxel_size_mm = 0.0;
  double max_distance_mm = 0.0;
  std::int64_t source_points = 0;  ///< source points used at this level
  /// Target points searched at this level: all of them, or the coarse sample's (TargetUse::kSingleAlignment)
  std::int64_t target_points = 0;
  int iterations = 0;
  bool converged = false;  ///< the update fell below the tolerances
  double rms_mm = 0.0;     ///< weighted RMS residual at the last iteration (mm)
  /// k-d tree searches at this level. A correspondence is searched again only when its source point has
  /// moved far enough that another target point could have become the nearest (exact, not approximate).
  std::int64_t searches = 0;
  double seconds = 0.0;  ///< wall time of this level (s)
};

/// What AlignIcp found.
struct IcpResult {
  Rigid3 T_target_source = Rigid3::Identity();  ///< x_target = T x_source (mm)
  double rms_mm = 0.0;           ///< RMS point-to-plane distance of the inliers at the final pose (mm)
  double inlier_fraction = 0.0;  ///< fraction of the finest level's source points that are inliers
  std::int64_t inliers = 0;      ///< their number
  int iterations = 0;            ///< over all levels
  bool converged = false;        ///< the last level stopped on the tolerances, not on max_iterations
  bool success = false;          ///< converged and every acceptance test passed
  double conditioning = 0.0;     ///< smallest / largest eigenvalue of the scaled 6x6 normal matrix
  /// The pose's spread implied by the residuals, Cov = s^2 H^-1 at the last iteration (docs/registration.md):
  /// largest standard deviation of the rotation (degrees) and of the source centroid's position (mm).
  double rotation_sd_deg = 0.0;
  double translation_sd_mm = 0.0;
  /// The robust scale of the residuals at the last iteration (1.4826 median |r|, floored at
  /// min_robust_scale_mm; mm): the noise that target_pose_sd_fraction refers to.
  double residual_scale_mm = 0.0;
  /// What sampling adds to the pose's standard error at the end, sd sqrt(1 - n/N) (mm; 0 with every
  /// point): the quantity the last level's growth drives below target_pose_sd_fraction times the noise.
  double sampling_sd_mm = 0.0;
  Timings timings_s;  ///< "icp": wall time of AlignIcp (target preparation not included), s
  /// One report per level, coarse to fine; a growing last level reports each size of its sample.
  std::vector<IcpLevelReport> levels;
  std::string message;  ///< one line: what was found, or why it failed

  /// One line for a log: "converged, 14 iterations, RMS 0.21 mm, 97.1 % inliers".
  std::string BriefReport() const;
};

/// How an IcpTarget is prepared (docs/registration.md, "A coarse target for one alignment").
enum class TargetUse {
  /// Any number of alignments and searches (merging sweeps, a cohort's reference): the k-d tree over
  /// every point is built at once.
  kShared,
  /// One alignment, at speed: ICP's coarse levels, whose search radius is beyond the grid's reach, search
  /// a k-d tree over a quarter of the points, each row kept on a hash of its row (CoarseTarget); the
  /// spacing comes from a grid; the tree over every point is built only if something asks for it. Targets
  /// under CoarseTarget::kMinPoints points are prepared as kShared.
  kSingleAlignment,
};

/// A kSingleAlignment target's coarse sample: a quarter of its points, chosen by a hash of their rows (in
/// row order), their k-d tree and their median spacing.
struct CoarseTarget {
  static constexpr Eigen::Index kMinPoints = 16384;  ///< smaller targets get no coarse sample
  Points3 positions;                                 ///< the sample's centred positions (mm)
  std::vector<std::uint32_t> rows;                   ///< their rows in the target
  std::unique_ptr<KdTree3> tree;                     ///< over `positions`
  double spacing_mm = 0.0;                           ///< median spacing of the sample (mm)
};

/// A target surface prepared once for any number of alignments: positions centred on their centroid
/// (so that a scanner frame far from the origin loses no precision), unit normals, a k-d tree.
class IcpTarget {
 public:
  /// @param[in] positions  #points by 3 (mm), >= 3 points
  /// @param[in] normals    #points by 3 unit normals (a zero row marks a point without a normal, never
  ///                       used as a correspondence)
  /// @param[in] name       names the target in error messages
  /// @param[in] use        kSingleAlignment for a target aligned to once (TargetUse)
  /// Throws Error(kBadInput) naming `name` for mismatched sizes, too few points or non-finite values.
  IcpTarget(const Points3& positions, const Points3& normals, const std::string& name = "target",
            TargetUse use = TargetUse::kShared);
  /// The same, taking over both arrays instead of copying them (the positions are centred in place).
  IcpTarget(Points3&& positions, Points3&& normals, const std::string& name = "target",
            TargetUse use = TargetUse::kShared);
  /// The same, estimating the normals with EstimateNormals on the target's own k-d tree (their sign is
  /// irrelevant to ICP). timings_s() says what that cost.
  IcpTarget(const Points3& positions, const NormalOptions& normal_options,
            const std::string& name = "target");
  ~IcpTarget();
  IcpTarget(const IcpTarget&) = delete;
  IcpTarget& operator=(const IcpTarget&) = delete;

  Eigen::Index size() const { return centred_.rows(); }
  /// The centroid subtracted from the positions (mm, target frame).
  const Eigen::Vector3d& origin() const { return origin_; }
  /// #points by 3 positions minus origin() (mm).
  const Points3& centred_positions() const { return centred_; }
  const Points3& normals() const { return normals_; }
  /// The k-d tree over every point. A kSingleAlignment target builds it on the first call (thread-safe;
  /// callers meanwhile wait).
  const KdTree3& tree() const;
  /// A kSingleAlignment target's coarse sample, else null.
  const CoarseTarget* coarse() const { return coarse_.get(); }
  /// Median distance between neighbouring target points (mm).
  double spacing_mm() const { return spacing_mm_; }
  /// Wall time (s) of "prepare" (copy, centring, tree or coarse sample, spacing) and, when they were
  /// estimated, "normals".
  const Timings& timings_s() const { return timings_s_; }

 private:
  Eigen::Vector3d origin_;
  Points3 centred_;
  Points3 normals_;
  mutable std::once_flag tree_once_;
  mutable std::unique_ptr<KdTree3> tree_;
  std::unique_ptr<CoarseTarget> coarse_;
  double spacing_mm_ = 0.0;
  Timings timings_s_;
  void Prepare(Points3 positions, const std::string& name, TargetUse use = TargetUse::kShared);
  void PrepareCoarse();
  void SetNormals(Points3 normals, Eigen::Index positions, const std::string& name);
};

/// The levels AlignIcp runs for these options, source and target (options.levels if given).
/// @param[in] source_points  number of source points considered (after patch restriction)
std::vector<IcpLevel> IcpLevelsFor(const IcpOptions& options, Eigen::Index source_points,
                                   double target_spacing_mm);

/// Aligns the source surface to the target: iteratively pairs subsampled source points with their
/// nearest target points and solves the linearised, robustly weighted normal equations (6 by 6, in
/// doubles, in the target's centred frame; OpenMP over correspondences with a fixed-order reduction, so
/// that results do not depend on the number of threads).
/// Never throws for a poor fit: the result says success = false and why. Throws Error(kUsage) for
/// invalid options and Error(kBadInput) for inconsistent inputs (sizes, non-finite values, kSymmetric
/// without source normals).
/// @param[in] target             prepared target
/// @param[in] source_positions   #m by 3 source points (mm, source frame)
/// @param[in] source_normals     #m by 3 unit normals, or empty (needed by kSymmetric and
///                               max_normal_angle_deg)
/// @param[in] T_target_source_initial  starting pose, e.g. from landmark alignment
IcpResult AlignIcp(const IcpTarget& target, const Points3& source_positions, const Points3& source_normals,
                   const Rigid3& T_target_source_initial, const IcpOptions& options = {});

}  // namespace pectus
