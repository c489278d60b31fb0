// pectus: the section profiles of the cross-section resampler (dissertation §4.3.1): planes at each grid
// row and column cut the surface into profiles, a curve is fitted to each profile's front envelope, and
// the curves are sampled and blended at the grid vertices.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "shape/core/geometry.h"
#include "shape/model/compute_chest_roi.h"
#include "shape/model/profile_fit.h"
#include "shape/model/shape_grid.h"

namespace pectus {

struct CrossSectionOptions;

/// The fitted section curves of one surface.
struct SectionCurves {
  std::vector<ProfileCurve> rows;     ///< one per grid row, depth(u); invalid where too few points
  std::vector<ProfileCurve> columns;  ///< one per grid column, depth(v); invalid where too few points
};

/// Cuts `surface` (a triangle mesh, or a point cloud when it has no faces; mm, in the frame of `roi`)
/// with the planes v = v_i (rows) and u = u_j (columns), keeps each profile's front envelope and fits a
/// curve to it (`options.fit`) over [u_0, u_last] or [v_0, v_last]. Profile points up to
/// `options.fit_margin_mm` beyond the ROI rectangle take part. Rows or columns are left empty when
/// `options.directions` does not use them.
/// @param[in] u, v  the grid's column and row positions (mm, increasing, equally spaced)
SectionCurves FitSectionCurves(const TriangleMesh& surface, const ChestRoi& roi, const Eigen::VectorXd& u,
                               const Eigen::VectorXd& v, const CrossSectionOptions& options);

/// How irregular a family of profile curves is: the mean squared third and fourth derivatives of its
/// curves (mm^-4, mm^-6) at grid positions on data. A cubic P-spline with a third-order penalty continues
/// a curve past the data with an error of about |d3w| g^3 / 6 at a distance g, and bridges a hole from data
/// at distances a below and b above with about |d4w| (a b)^2 / 24.
struct ProfileRoughness {
  double d3 = 0.0, d4 = 0.0;
};

/// The roughness of `curves` at the positions `t` (mm), by differences `h` (mm) apart.
ProfileRoughness FamilyRoughness(const std::vector<ProfileCurve>& curves, const Eigen::VectorXd& t, double h);

/// The section curves sampled at a grid.
struct BlendedGrid {
  Eigen::VectorXd depth;    ///< per vertex (row-major), mm; 0 where unknown
  Eigen::VectorXd gap;      ///< distance to the nearest profile data of a curve through it, mm
  std::vector<bool> known;  ///< false where no fitted curve passes through the vertex
};

/// Samples the row and column curves at each vertex of `grid` (columns at `u`, rows at `v`); where both
/// pass through a vertex they are blended by the inverse of each one's expected squared error there: the
/// fit's noise `noise_mm2` plus the error of bridging the hole or continuing past the data, with the
/// derivatives typical of its family (`row_roughness`, `column_roughness`). So a vertex on data in one
/// direction takes that direction, and inside a hole the direction along which the chest bends less
/// regularly gives way.
BlendedGrid BlendSectionCurves(const SectionCurves& curves, const GridSize& grid, const Eigen::VectorXd& u,
                               const Eigen::VectorXd& v, const ProfileRoughness& row_roughness,
                               const ProfileRoughness& column_roughness, double noise_mm2);

}  // namespace pectus
