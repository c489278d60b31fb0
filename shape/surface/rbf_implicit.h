// pectus: an implicit surface from oriented points by partition-of-unity blending of local polyharmonic
// RBF fits with off-surface constraints (Carr et al. 2001; Ohtake et al. 2003), fitted lazily cell by
// cell where it is evaluated. The method and its parameters: docs/reconstruction.md.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "shape/core/geometry.h"

namespace pectus {

/// Options of RbfImplicit. Lengths in mm.
struct RbfImplicitOptions {
  /// Edge of a partition-of-unity cell (mm). Cell i blends in with weight W(|x - c_i| / cell_size_mm),
  /// W the Wendland function (1 - r)^4 (4 r + 1), so every point has at least one cell covering it.
  double cell_size_mm = 4.0;
  /// A cell next to data fits the data within fit_radius_factor * cell_size_mm of its centre.
  double fit_radius_factor = 1.25;
  /// A cell whose centre lies a distance d from the data along the surface (over a hole, or beyond the
  /// edge of an open scan; d is measured in the tangent plane of the nearest point, so a cell just above
  /// or below the data has d = 0) fits the data within fit_radius_factor * cell_size_mm + hole_context * d,
  /// so that it sees the rim all around a hole.
  double hole_context = 3.0;
  /// Spacing of the RBF centres next to data (mm): the points averaged per cube of this side. Cells
  /// over holes use coarser centres (doubled spacing per level) so a fit never has more than
  /// max_centres kernels. The on-surface constraints are the points averaged at half this spacing.
  double centre_spacing_mm = 2.0;
  /// Off-surface constraints at y +- eps n with values +-eps (Carr et al. 2001, Sec. 3.1), per centre;
  /// eps is halved (up to three times, then dropped) where the point would lie nearer other data.
  double off_surface_distance_mm = 1.0;
  /// Weight of an off-surface constraint relative to the on-surface data it stands for.
  double off_surface_weight = 0.5;
  /// Bending-energy weight of each local fit (dimensionless, see LocalRbf); larger = smoother.
  double smoothing = 1e-3;
  /// Cells whose centre is farther than this from every data point are undefined (mm): the surface
  /// ends there. Holes up to about twice this wide get a surface.
  double max_fill_distance_mm = 20.0;
  /// Widest hole to be filled (mm). A cell more than half a cell from the data along the surface is
  /// fitted only if data lies ahead of it (away from its nearest data) within this width, i.e. it is over
  /// a hole; beyond the edge of an open scan it is undefined (the surface there would be trimmed away).
  /// 0 = every cell within max_fill_distance_mm is fitted.
  double max_hole_size_mm = 0.0;
  /// At most this many kernels per local fit.
  int max_centres = 60;

  /// False, with the reason in `why`, if a value is out of range.
  bool IsValid(std::string* why) const;
};

/// How well the implicit matches its constraints (dissertation Eq. 11).
struct RbfFittingAccuracy {
  double fitting_accuracy_mm = 0.0;  ///< max |s(x_i) - f_i| over on- and off-surface constraints
  double on_surface_max_mm = 0.0;    ///< max |s(p_i)| over the on-surface constraints
  double on_surface_rms_mm = 0.0;    ///< RMS of s(p_i) over the on-surface constraints
  double on_surface_p95_mm = 0.0;    ///< 95th percentile of |s(p_i)|
  double off_surface_max_mm = 0.0;   ///< max |s(y_j +- eps n_j) -+ eps| over the off-surface constraints
  std::int64_t num_on_surface = 0;   ///< on-surface constraints checked
  std::int64_t num_off_surface = 0;  ///< off-surface constraints checked
};

/// s(x): negative inside, positive outside (the side the normals point to), zero on the surface, about
/// the signed distance (mm) near the data. Cells are fitted on first use; Evaluate is therefore not
/// const and must not be called from several threads at once (it is parallel inside, with OpenMP).
class RbfImplicit {
 public:
  /// Builds the centre levels. Throws Error(kUsage) for invalid options.
  /// @param[in] positions  #points by 3 input points (mm), copied
  /// @param[in] normals    #points by 3 unit normals pointing out of the object (toward the scanner)
  RbfImplicit(const Points3& positions, const Points3& normals, const RbfImplicitOptions& options);
  /// The same for weighted points (e.g. points already averaged per cube).
  /// @param[in] counts  #points, > 0: the input points each stands for
  RbfImplicit(const Points3& positions, const Points3& normals, const Eigen::VectorXd& counts,
              const RbfImplicitOptions& options);
  ~RbfImplicit();
  RbfImplicit(const RbfImplicit&) = delete;
  RbfImplicit& operator=(const RbfImplicit&) = delete;

  /// s at each query (mm), NaN where no cell is defined.
  /// @param[in]  queries  #queries by 3 (mm)
  /// @param[out] values   #queries
  void Evaluate(const Points3& queries, Eigen::VectorXd* values);

  /// Evaluates s at the constraints of the fits: the on-surface points (the input points averaged per
  /// cube of half the centre spacing) and the off-surface points.
  RbfFittingAccuracy FittingAccuracy();

  /// The averaged points at the centre spacing (#centres by 3, mm): near the surface everywhere there
  /// is data, so good seeds for isosurfacing.
  const Points3& Seeds() const;

  /// Cells fitted so far, and how many of them are undefined (no data near enough).
  std::int64_t num_cells() const;
  std::int64_t num_undefined_cells() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace pectus
