// pectus: resampling a registered chest surface onto the ROI grid by many parallel cross-sections
// (dissertation §4.3.1): each section plane cuts the surface into a profile, a curve fitted to the
// profile is sampled at the grid positions. Holes inside the data are interpolated, missing data beyond
// its convex hull extrapolated, which linear interpolation cannot do.
#pragma once

#include <Eigen/Core>
#include <string>

#include "shape/core/geometry.h"
#include "shape/core/landmarks.h"
#include "shape/core/timings.h"
#include "shape/model/compute_chest_roi.h"
#include "shape/model/grid_inpainting.h"
#include "shape/model/profile_fit.h"
#include "shape/model/shape_grid.h"

namespace pectus {

/// Which families of section planes are used.
enum class SectionDirections {
  kRows,     ///< planes across the chest at each grid row (profiles depth(u))
  kColumns,  ///< planes along the chest at each grid column (profiles depth(v))
  kBoth,     ///< both, blended per vertex by how close each profile's data come to the vertex
};

/// "rows", "columns" or "both"; throws Error(kUsage) otherwise.
SectionDirections ParseSectionDirections(const std::string& text);
std::string ToString(SectionDirections directions);

/// How a surface is resampled.
struct CrossSectionOptions {
  GridSize grid;          ///< 51 x 101 vertices by default
  ProfileFitOptions fit;  ///< P-spline by default
  SectionDirections directions = SectionDirections::kBoth;
  /// Profile points up to this far beyond the ROI rectangle take part in the fits (>= 0, mm).
  double fit_margin_mm = 25.0;
  /// Point clouds (no faces): points within this distance of a section plane form its profile (> 0, mm).
  double slab_half_width_mm = 0.75;
  /// Front envelope: within each `envelope_bin_mm` of a profile only points within `envelope_depth_mm`
  /// of the most anterior one are kept, so the back of a closed torso or a fold does not enter the fit.
  double envelope_bin_mm = 2.0;
  double envelope_depth_mm = 15.0;
  /// A profile with fewer points is not fitted (>= 2).
  int min_profile_points = 8;
  /// Grid vertices far from every profile's data (holes, and past the scan's edge) are filled in 2D from
  /// the vertices around them (biharmonic inpainting of the depths), not by 1D profiles that bridge the
  /// hole in one direction only.
  GridHoleFillOptions holes;
  /// True (default): the profiles are sampled and the holes filled on the ROI grid grown by whole
  /// spacings up to `fit_margin_mm` on each side, then cut back to the ROI; a hole across the ROI's border
  /// whose data go on beyond it is then inside that grid and is filled in 2D like a hole inside the ROI.
  /// False: the grid covers the ROI only, and holes across its border keep the profiles' estimate.
  bool extend_grid = true;

  /// False, with the reason, for a value out of range.
  bool IsValid(std::string* why) const;
};

/// What the resampling produced.
struct CrossSectionResult {
  ChestRoi roi;
  GridSize grid;
  /// The resampled surface in the input's frame: #grid vertices (row-major: i * lateral + j, row i
  /// along the sternal line) and GridFaces(). Scalars: "depth_mm" (w), "data_gap_mm" (distance from the
  /// vertex to the nearest profile data point along the profile that supports it best: 0 on data,
  /// > 0 in holes and beyond the data).
  TriangleMesh mesh;
  Eigen::VectorXd shape_vector;         ///< ToShapeVector(mesh.vertices.positions), 3m numbers, mm
  int profiles_fitted = 0;              ///< section profiles with a curve
  int profiles_unfitted = 0;            ///< section profiles with too few points
  Eigen::Index profile_points = 0;      ///< points in all fitted profiles
  double fit_rms_mm = 0.0;              ///< RMS residual of all profile fits, mm
  double max_data_gap_mm = 0.0;         ///< largest "data_gap_mm" over the grid
  double supported_fraction = 0.0;      ///< fraction of grid vertices with data_gap_mm <= 2 grid spacings
  Eigen::Index vertices_inpainted = 0;  ///< grid vertices filled in 2D (CrossSectionOptions::holes)
  ProfileFitKind fit_kind = ProfileFitKind::kSmoothingSpline;  ///< the profiles' curves
  /// Wall time, s: "fit_profiles", "blend" (the sampled curves blended, corners extrapolated),
  /// "fill_holes", "grid" (the ROI's vertices back in the surface's frame).
  Timings timings_s;
  /// One line: grid, profiles and fit, data gap, vertices filled in 2D.
  std::string BriefReport() const;
};

/// Resamples `surface` (a triangle mesh, or a point cloud when it has no faces; mm, in the frame of
/// `roi`) on the ROI grid. Throws Error(kBadInput) naming `what` if some grid vertex has no fitted
/// profile through it (no surface data near its row or its column), Error(kUsage) for invalid options.
CrossSectionResult ResampleCrossSections(const TriangleMesh& surface, const ChestRoi& roi,
                                         const CrossSectionOptions& options = {},
                                         const std::string& what = "surface");

/// ComputeChestRoi from the landmarks, then ResampleCrossSections: one subject to its shape vector.
CrossSectionResult ResampleSurface(const TriangleMesh& surface, const LandmarkSet& landmarks,
                                   const ChestRoiOptions& roi_options = {},
                                   const CrossSectionOptions& options = {},
                                   const std::string& what = "surface");

}  // namespace pectus
