// pectus: fine rigid alignment of two surfaces sampled as points: point-to-plane ICP (Chen and Medioni
// 1992) or symmetric ICP (Rusinkiewicz 2019), robust, gated, coarse to fine.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "registration/kdtree.h"
#include "registration/normals.h"
#include "registration/robust_loss.h"
#include "shape/core/geometry.h"

namespace pectus {

/// The error that ICP minimises.
enum class IcpMethod {
  kPointToPlane,  ///< sum w ((T p - q) . n_q)^2, target normals only
  kSymmetric,     ///< sum w ((T p - q) . (n_p + n_q))^2 with the rotation split between both sides
};

/// Parses "point-to-plane" or "symmetric"; throws Error(kUsage) otherwise.
IcpMethod ParseIcpMethod(const std::string& name);
std::string ToString(IcpMethod method);

/// One stage of coarse-to-fine ICP.
struct IcpLevel {
  double voxel_size_mm = 0.0;    ///< source subsampling cube (mm); 0 = every source point
  double max_distance_mm = 0.0;  ///< correspondences farther apart are dropped (mm), > 0
  int max_iterations = 30;       ///< iterations at this level, >= 1
};

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

  /// Coarse to fine. Empty = automatic: one level per entry of `auto_level_points`, the source
  /// subsampled by voxels to about that many points, the gate starting at `initial_max_distance_mm`
  /// and shrinking fourfold per level, down to 3 times the target's point spacing.
  std::vector<IcpLevel> levels;
  std::vector<int> auto_level_points = {1000, 3000, 10000};  ///< source points per automatic level
  double initial_max_distance_mm = 20.0;                    ///< gate of the first automatic level (mm)
  int auto_max_iterations = 30;                             ///< iterations per automatic level

  /// A level stops when an update rotates by less than this (degrees) and moves by less than
  /// `translation_tolerance_mm`, or when the pose is back where it was two iterations before (a cycle
  /// between correspondence sets); each level above the last uses ten times its finer neighbour's values.
  double rotation_tolerance_deg = 1e-3;
  double translation_tolerance_mm = 2e-3;

  /// Restrict the source to surface patches: points within `patch_radius_mm` of any of these centres
  /// (source frame, mm), as around landmarks. Empty = the whole source.
  std::vector<Eigen::Vector3d> patch_centres;
  double patch_radius_mm = 0.0;

  /// Acceptance. A result that misses any of these is returned with success = false and the reason.
  double max_rms_mm = 1.0;             ///< RMS point-to-plane distance of the inliers (mm)
  double min_inlier_fraction = 0.3;    ///< source points (finest level) with a target point within reach
  double inlier_distance_mm = 0.0;     ///< that reach (mm); 0 = the last level's gate
  double min_conditioning = 1e-5;      ///< smallest / largest eigenvalue of the scaled 6x6 normal matrix
  int min_correspondences = 30;        ///< fewer at any iteration is a failure

  /// False, with the reason in `why`, if a value is out of range.
  bool IsValid(std::string* why) const;
};

/// What happened at one level.
struct IcpLevelReport {
  double voxel_size_mm = 0.0;
  double max_distance_mm = 0.0;
  std::int64_t source_points = 0;   ///< source points used at this level
  int iterations = 0;
  bool converged = false;           ///< the update fell below the tolerances
  double rms_mm = 0.0;              ///< weighted RMS residual at the last iteration (mm)
};

/// What AlignIcp found.
struct IcpResult {
  Rigid3 T_target_source = Rigid3::Identity();  ///< x_target = T x_source (mm)
  double rms_mm = 0.0;            ///< RMS point-to-plane distance of the inliers at the final pose (mm)
  double inlier_fraction = 0.0;   ///< fraction of the finest level's source points that are inliers
  std::int64_t inliers = 0;       ///< their number
  int iterations = 0;             ///< over all levels
  bool converged = false;         ///< the last level stopped on the tolerances, not on max_iterations
  bool success = false;           ///< converged and every acceptance test passed
  double conditioning = 0.0;      ///< smallest / largest eigenvalue of the scaled 6x6 normal matrix
  double seconds = 0.0;           ///< wall time of AlignIcp (target preparation not included)
  std::vector<IcpLevelReport> levels;
  std::string message;            ///< one line: what was found, or why it failed

  /// One line for a log: "converged, 14 iterations, RMS 0.21 mm, 97.1 % inliers".
  std::string BriefReport() const;
};

/// A target surface prepared once for any number of alignments: positions centred on their centroid
/// (so that a scanner frame far from the origin loses no precision), unit normals, a k-d tree.
class IcpTarget {
 public:
  /// @param[in] positions  #points by 3 (mm), >= 3 points
  /// @param[in] normals    #points by 3 unit normals (a zero row marks a point without a normal, never
  ///                       used as a correspondence)
  /// @param[in] name       names the target in error messages
  /// Throws Error(kBadInput) naming `name` for mismatched sizes, too few points or non-finite values.
  IcpTarget(const Points3& positions, const Points3& normals, const std::string& name = "target");
  /// The same, estimating the normals with EstimateNormals on the target's own k-d tree (their sign is
  /// irrelevant to ICP). normal_seconds() says what that cost.
  IcpTarget(const Points3& positions, const NormalOptions& normal_options, const std::string& name = "target");
  ~IcpTarget();
  IcpTarget(const IcpTarget&) = delete;
  IcpTarget& operator=(const IcpTarget&) = delete;

  Eigen::Index size() const { return centred_.rows(); }
  /// The centroid subtracted from the positions (mm, target frame).
  const Eigen::Vector3d& origin() const { return origin_; }
  /// #points by 3 positions minus origin() (mm).
  const Points3& centred_positions() const { return centred_; }
  const Points3& normals() const { return normals_; }
  const KdTree3& tree() const { return *tree_; }
  /// Median distance between neighbouring target points (mm).
  double spacing_mm() const { return spacing_mm_; }
  /// Seconds spent preparing (copy, centring, tree), normals excluded.
  double seconds() const { return seconds_; }
  /// Seconds spent estimating normals (0 when they were given).
  double normal_seconds() const { return normal_seconds_; }

 private:
  Eigen::Vector3d origin_;
  Points3 centred_;
  Points3 normals_;
  std::unique_ptr<KdTree3> tree_;
  double spacing_mm_ = 0.0;
  double seconds_ = 0.0;
  double normal_seconds_ = 0.0;
  void Prepare(const Points3& positions, const std::string& name);
};

/// The levels AlignIcp runs for these options, source and target (options.levels if given).
/// @param[in] source_points  number of source points considered (after patch restriction)
std::vector<IcpLevel> IcpLevelsFor(const IcpOptions& options, Eigen::Index source_points, double target_spacing_mm);

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
