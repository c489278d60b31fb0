// pectus: the point levels of the RBF implicit (shape/rbf_implicit.h): input points averaged per cube at
// a spacing, with counts, k-d tree and off-surface distances, and the local problem a cell fits from them.
#pragma once

#include <cstdint>
#include <memory>
#include <utility>
#include <vector>

#include "registration/kdtree.h"
#include "shape/core/geometry.h"
#include "shape/surface/local_rbf.h"

namespace pectus {

/// Points averaged per cube (and per side of a thin sheet: points whose normals oppose the first point of
/// their cube are averaged apart), with their counts. Deterministic.
struct RbfLevel {
  double spacing = 0.0;                 ///< cube side (mm)
  Points3 positions;                    ///< averaged points (mm)
  Points3 normals;                      ///< their unit normals
  Eigen::VectorXd counts;               ///< input points averaged into each
  Eigen::VectorXd eps_plus, eps_minus;  ///< off-surface distances per point (mm; 0 = none), centre levels
  std::unique_ptr<KdTree3> tree;        ///< over positions
};

/// Averages weighted points per cube of side `spacing` into `level` (its tree included).
/// @param[in] positions, normals  #points by 3 (mm, unit); normals may be empty (0 rows): then every
///                                cube gives one point and `level` has no normals
/// @param[in] counts              weight of each point (the input points it stands for)
void AverageByVoxel(const Points3& positions, const Points3& normals, const Eigen::VectorXd& counts,
                    double spacing, RbfLevel* level);

/// Off-surface distances of a centre level (Carr et al. 2001, Sec. 3.1: an off-surface point must not lie
/// nearer to other data than to its own point): eps, halved up to three times until the point y +- eps n
/// is at least 0.7 eps from every point of `fine`, else 0 (no constraint on that side).
void SetOffSurfaceDistances(const RbfLevel& fine, double eps_mm, RbfLevel* level);

/// Wendland's C2 function (1 - r)^4 (4 r + 1), support [0, 1].
inline double WendlandC2(double r) {
  if (r >= 1.0) return 0.0;
  const double a = 1.0 - r;
  const double a2 = a * a;
  return a2 * a2 * (4.0 * r + 1.0);
}

/// (index, squared distance) pairs, as KdTree3::Radius returns them.
using LevelNeighbours = std::vector<std::pair<std::uint32_t, double>>;

/// The local fit of one cell: on-surface constraints (value 0) at the `rows` of `row_level`, kernels at
/// the `centres` of `centre_level` with their off-surface pairs (value +-eps), each weighted by its count
/// times WendlandC2(distance / radius), the off-surface ones by off_surface_weight more.
/// @param[in] origin, radius  the cell's fitting ball (mm): the local frame of the fit
LocalRbfProblem LocalProblem(const RbfLevel& row_level, const LevelNeighbours& rows,
                             const RbfLevel& centre_level, const LevelNeighbours& centres,
                             const Eigen::Vector3d& origin, double radius, double off_surface_weight);

}  // namespace pectus
