// pectus: one sweep of a scan prepared for alignment (normals, border points, a k-d tree, a subsample),
// and the point-to-plane correspondences between two such sweeps at given poses.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "registration/icp.h"
#include "shape/core/geometry.h"

namespace pectus {

/// Options of PrepareSweep.
struct SweepSurfaceOptions {
  /// k of the PCA normals (>= 3). 32 rather than 16: the normals' noise, which the joint adjustment
  /// counts against the information of every direction (TrackerAdjustmentOptions::min_pinned_ratio),
  /// halves, and the narrow overlaps of a chest's strips pin more (issue-13 grid at 2-4 mm, 15-40 %:
  /// the whole line met in 13 and 12 of 36 cells against 11 and 8; docs/benchmarks/merge.md).
  int normal_neighbours = 32;
  int border_neighbours = 24;  ///< k of the border test (>= 4)
  /// A point is on the border of the sweep (its edge or the rim of a hole in it) when its
  /// border_neighbours nearest neighbours, seen from it in its tangent plane, leave an angular gap wider
  /// than this (degrees): about 180 on an edge; inside, at most 90 on a range grid and wider than 135
  /// with probability 0.05 % for 24 uniformly random neighbours (unstructured sampling).
  double border_gap_deg = 135.0;
  /// Points whose normal is farther than this (degrees) from the sweep's mean normal, the scanner's
  /// line of sight, are seen at a grazing angle, where triangulation scanners are least accurate (Turk
  /// and Levoy 1994 weight them down); they are left out of every correspondence. 90 = off. On the
  /// Stanford bunny 65 brings the joint solution 0.05 mm nearer the published alignment than 90.
  double max_view_angle_deg = 65.0;
  /// Of a sweep whose scanner moved along it (moving_scanner_density_ratio), the line of sight a point's
  /// view angle is taken from: the sweep's mean normal over a cube of half side this many sweep widths
  /// about the point (the width: the sweep's narrow extent across its mean normal, sqrt(12) times the
  /// standard deviation of its points projected on the plane normal to it, along their narrow principal
  /// axis). Normals are turned to its side too. A handheld wand travels along its sweep facing the skin,
  /// so a strip wrapped around a chest is seen head-on at its ends, where the sweep's mean normal is
  /// 60-90 degrees off (21-27 % of a 3-strip chest sweep's points were left out as grazing). 0: one line of
  /// sight, the sweep's mean normal, for every sweep.
  double sight_radius_widths = 0.5;
  /// A sweep's scanner moved along it when its sampling density 55-80 degrees from its mean normal is at
  /// least this fraction of that within 30 degrees: a scanner standing still samples a surface turned by
  /// theta at cos(theta) of the density (the Stanford bunny's ten scans: 0.44-0.54), a wand facing the
  /// skin all along evenly (the synthetic chest strips: 0.86-1.06). 0: every sweep; > 1: none.
  double moving_scanner_density_ratio = 0.7;
  /// Correspondences are weighted by (cos a_p cos a_q)^view_weight_power, a the angle between a
  /// point's normal and its sweep's line of sight (the confidence of Turk and Levoy 1994); 0 = off.
  double view_weight_power = 0.0;
  /// Cube side of the subsample that correspondences start from, in point spacings (>= 1).
  double sample_spacings = 2.0;
  /// A correspondence's plane on this sweep passes through the mean of the point's this many nearest
  /// points of the sweep (those within the gate, neither on the border nor grazing), normal their mean
  /// normal, as ICP's (IcpOptions::plane_points): the sweep's own noise enters each residual about this
  /// many times less (issue-13 grid at 2-4 mm, >= 15 %: the whole line met in 15 and 14 of 36 cells on
  /// seeds 1 and 2 against 15 and 11 with the nearest point's plane, about even on seeds 3 and 4;
  /// docs/benchmarks/merge.md). 1 to kMaxPlanePoints.
  int plane_points = 4;

  /// False, with the reason in `why`, if a value is out of range.
  bool IsValid(std::string* why) const;
};

/// A sweep prepared once, in its own frame.
struct SweepSurface {
  const PointCloud* cloud = nullptr;  ///< the sweep (not owned; must outlive this)
  Points3 normals;                    ///< #points by 3, unit, one consistent side (see FlipNormals)
  std::vector<std::uint8_t> border;   ///< 1 for points on the sweep's border
  std::vector<std::uint8_t> grazing;  ///< 1 for points seen at a grazing angle (max_view_angle_deg)
  std::vector<float> confidence;      ///< per point, cos(angle to the line of sight)^view_weight_power
  /// Point-to-plane target over the sweep; border points carry a zero normal there, so that ICP never
  /// pairs a point with the edge of the other sweep (Turk and Levoy 1994), which would pull the sweeps
  /// toward each other's edges.
  std::unique_ptr<IcpTarget> target;
  std::vector<std::uint32_t> samples;  ///< rows of an even subsample (voxels of sample_spacings)
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();  ///< mm, sweep frame
  double spacing_mm = 0.0;                             ///< median distance between neighbouring points
  /// Expected squared angular error of a normal (rad^2 per tangent axis): 2 c / k for PCA over k
  /// neighbours whose surface variation (lambda_min / sum of lambdas) has the median c over the sweep.
  double normal_variance = 0.0;
  /// The scanner moved along the sweep (SweepSurfaceOptions::moving_scanner_density_ratio): its points'
  /// lines of sight follow the sweep (sight_radius_widths).
  bool scanner_moved = false;
  int plane_points = 1;  ///< SweepSurfaceOptions::plane_points

  /// Reverses every normal (the sweep's side; the target's normals are sign-free).
  void FlipNormals();
};

/// Normals by PCA oriented by propagation (Hoppe et al. 1992), border points, target and subsample.
/// Throws Error(kBadInput) naming `name` for fewer than 10 points or non-finite coordinates.
SweepSurface PrepareSweep(const PointCloud& cloud, const SweepSurfaceOptions& options,
                          const std::string& name);

/// A row of no point: a correspondence whose points' rows are not known.
inline constexpr std::uint32_t kUnknownRow = 0xffffffffu;

/// A point of sweep j on the tangent plane of sweep i: the residual is n . (T_j p - T_i q) in the world.
struct SweepCorrespondence {
  std::size_t i = 0, j = 0;  ///< target sweep i, source sweep j
  Eigen::Vector3d p;         ///< mm, in sweep j's frame
  Eigen::Vector3d q, n;      ///< mm and unit normal, in sweep i's frame
  double weight = 1.0;       ///< confidence of the pair, in (0, 1]
  /// The rows of p in sweep j and of q in sweep i (kUnknownRow: not known, counted as a point no other
  /// correspondence uses): a point's noise enters every correspondence that uses it, which
  /// AdjustPosesToTracker counts (TrackerAdjustmentOptions::count_shared_points).
  std::uint32_t p_row = kUnknownRow, q_row = kUnknownRow;
};

/// Pairs evenly strided samples of sweep j (at most max_samples) with their nearest points of sweep i at
/// the poses T_world_sweep, keeping pairs closer than gate_mm (and than i's point spacing along the
/// tangent plane: farther is a point beyond i's edge paired with the edge) whose normals (same side) differ
/// by less than max_angle_deg, whose point of i is not on i's border and neither of which is grazing.
std::vector<SweepCorrespondence> FindSweepCorrespondences(const std::vector<SweepSurface>& sweeps,
                                                          const std::vector<Rigid3>& T_world_sweep,
                                                          std::size_t i, std::size_t j, int max_samples,
                                                          double gate_mm, double max_angle_deg = 45.0);

/// The same from the given rows of sweep j (e.g. every point of its overlap with i) instead of its
/// subsample: at most max_samples of them, evenly strided (<= 0: every row).
std::vector<SweepCorrespondence> FindSweepCorrespondences(const std::vector<SweepSurface>& sweeps,
                                                          const std::vector<Rigid3>& T_world_sweep,
                                                          std::size_t i, std::size_t j,
                                                          const std::vector<std::uint32_t>& rows,
                                                          int max_samples, double gate_mm,
                                                          double max_angle_deg = 45.0);

/// RMS of the point-to-plane residuals of `pairs` at the poses T_world_sweep (mm); 0 if empty.
double PointToPlaneRms(const std::vector<SweepCorrespondence>& pairs,
                       const std::vector<Rigid3>& T_world_sweep);

}  // namespace pectus
