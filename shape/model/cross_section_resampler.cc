#include "shape/model/cross_section_resampler.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <sstream>

#include "shape/core/enum_names.h"
#include "shape/core/error.h"
#include "shape/model/cross_section_profiles.h"

namespace pectus {
namespace {

// The grid of `roi` with `extra_u` more columns on each side and `extra_v` more rows at the top and the
// bottom, at the same spacings: the ROI rectangle grown to match.
ChestRoi ExtendedRoi(const ChestRoi& roi, const GridSize& grid, int extra_u, int extra_v) {
  const double spacing_u = roi.width() / (grid.lateral - 1), spacing_v = roi.height() / (grid.sternal - 1);
  ChestRoi out = roi;
  out.u_min -= extra_u * spacing_u, out.u_max += extra_u * spacing_u;
  out.v_min -= extra_v * spacing_v, out.v_max += extra_v * spacing_v;
  return out;
}

}  // namespace

constexpr EnumNames<SectionDirections, 3> kSectionDirectionNames{{{SectionDirections::kRows, "rows"},
                                                                  {SectionDirections::kColumns, "columns"},
                                                                  {SectionDirections::kBoth, "both"}}};

SectionDirections ParseSectionDirections(const std::string& text) {
  return ParseEnum(kSectionDirectionNames, text, [&] {
    return "section directions '" + text + "' are not " +
           ListEnumNames(kSectionDirectionNames, "'", ", ", " or ");
  });
}

std::string ToString(SectionDirections directions) {
  return EnumToString(kSectionDirectionNames, directions, "both");
}

bool CrossSectionOptions::IsValid(std::string* why) const {
  auto fail = [&](const std::string& m) {
    if (why != nullptr) *why = m;
    return false;
  };
  if (!grid.IsValid(why) || !fit.IsValid(why)) return false;
  if (!(fit_margin_mm >= 0.0) || !std::isfinite(fit_margin_mm)) return fail("fit margin must be >= 0 mm");
  if (!(slab_half_width_mm > 0.0) || !std::isfinite(slab_half_width_mm))
    return fail("slab half-width must be > 0 mm");
  if (!(envelope_bin_mm > 0.0) || !(envelope_depth_mm > 0.0) || !std::isfinite(envelope_bin_mm) ||
      !std::isfinite(envelope_depth_mm)) {
    return fail("front envelope bin and depth must be > 0 mm");
  }
  if (min_profile_points < 2) return fail("a profile needs at least 2 points");
  return holes.IsValid(why);
}

CrossSectionResult ResampleCrossSections(const TriangleMesh& surface, const ChestRoi& roi,
                                         const CrossSectionOptions& options, const std::string& what) {
  std::string why;
  if (!options.IsValid(&why)) ThrowUsage(why);
  surface.Validate(what);
  const GridSize& grid = options.grid;
  const double spacing_u = roi.width() / (grid.lateral - 1), spacing_v = roi.height() / (grid.sternal - 1);

  // 1. The working grid: the ROI's, grown by whole spacings up to the fit margin on each side when
  //    options.extend_grid, so that a hole across the ROI's border whose data go on beyond it lies inside
  //    the working grid (steps 3 and 5). (extra_u, extra_v): columns and rows added on each side.
  auto extra = [&](double spacing) {  // whole spacings within the margin; none for a degenerate ROI
    return options.extend_grid && spacing > 0.0
               ? static_cast<int>(std::floor(options.fit_margin_mm / spacing + 1e-9))
               : 0;
  };
  const int extra_u = extra(spacing_u), extra_v = extra(spacing_v);
  const GridSize work{grid.lateral + 2 * extra_u, grid.sternal + 2 * extra_v};
  const ChestRoi work_roi = ExtendedRoi(roi, grid, extra_u, extra_v);
  const Eigen::VectorXd u = GridLateralPositions(roi, grid), v = GridSternalPositions(roi, grid);
  const Eigen::VectorXd work_u = GridLateralPositions(work_roi, work);
  const Eigen::VectorXd work_v = GridSternalPositions(work_roi, work);
  auto roi_index = [&](int i, int j) { return work.Index(i + extra_v, j + extra_u); };

  // 2. A curve through each row's and column's section profile (cross_section_profiles.h).
  CrossSectionResult result;
  std::optional<Timings::Scope> stage(std::in_place, &result.timings_s, "fit_profiles");
  const SectionCurves curves = FitSectionCurves(surface, roi, work_u, work_v, options);
  result.roi = roi;
  result.grid = grid;
  double sum_sq = 0.0;
  for (const auto* family : {&curves.rows, &curves.columns}) {
    for (const ProfileCurve& c : *family) {
      if (c.valid()) {
        ++result.profiles_fitted;
        result.profile_points += c.num_points();
        sum_sq += c.rms_residual() * c.rms_residual() * static_cast<double>(c.num_points());
      } else {
        ++result.profiles_unfitted;
      }
    }
  }
  result.fit_rms_mm =
      result.profile_points > 0 ? std::sqrt(sum_sq / static_cast<double>(result.profile_points)) : 0.0;

  // 3. The curves sampled at the working grid, row and column blended by each one's expected error there
  //    (the derivatives typical of each family taken over the ROI).
  stage.emplace(&result.timings_s, "blend");
  const double h = options.fit.knot_spacing_mm;
  const double noise_mm2 = std::max(1e-4, result.fit_rms_mm * result.fit_rms_mm);
  BlendedGrid blend = BlendSectionCurves(curves, work, work_u, work_v, FamilyRoughness(curves.rows, u, h),
                                         FamilyRoughness(curves.columns, v, h), noise_mm2);
  Eigen::VectorXd& depth = blend.depth;
  Eigen::VectorXd& gap = blend.gap;

  // 4. Vertices that no fitted section passes through (a corner beyond the data in both directions).
  ExtrapolateAlongGridLines(work, work_u, work_v, options.fit,
                            std::min({options.min_profile_points, work.lateral, work.sternal}), &blend.known,
                            &depth, &gap);
  const Eigen::Index m = grid.num_vertices();
  Eigen::Index missing = 0, first_missing = -1;
  for (int i = 0; i < grid.sternal; ++i) {
    for (int j = 0; j < grid.lateral; ++j) {
      if (!blend.known[roi_index(i, j)] && missing++ == 0) first_missing = grid.Index(i, j);
    }
  }
  if (missing > 0) {
    const auto i = static_cast<int>(first_missing / grid.lateral),
               j = static_cast<int>(first_missing % grid.lateral);
    ThrowBadInput(what, std::to_string(missing) + " of " + std::to_string(m) +
                            " grid vertices have no fitted section near them (first: row " +
                            std::to_string(i) + ", column " + std::to_string(j) +
                            "); the surface does not reach that part of the ROI");
  }
  // Working vertices beyond the ROI that nothing reaches count as beyond the data.
  for (Eigen::Index k = 0; k < work.num_vertices(); ++k) {
    if (!blend.known[k]) gap[k] = std::numeric_limits<double>::infinity();
  }

  // 5. Vertices far from every profile's data: filled in 2D from the vertices around them, which sees a
  //    feature narrower than the hole (the sternal groove) from all sides (docs/model.md).
  stage.emplace(&result.timings_s, "fill_holes");
  std::vector<bool> filled;
  FillGridHoles(work, spacing_u, spacing_v, gap, options.holes, &depth, &filled, work_u);

  // 6. The ROI's part of the working grid, back in the surface's frame.
  stage.emplace(&result.timings_s, "grid");
  Points3 grid_uvw(m, 3);
  Eigen::VectorXd roi_depth(m), roi_gap(m);
  for (int i = 0; i < grid.sternal; ++i) {
    for (int j = 0; j < grid.lateral; ++j) {
      const Eigen::Index k = grid.Index(i, j), w = roi_index(i, j);
      roi_depth[k] = depth[w];
      roi_gap[k] = gap[w];
      result.vertices_inpainted += filled[w] ? 1 : 0;
      grid_uvw.row(k) << u[j], v[i], depth[w];
    }
  }
  const double spacing = std::max(spacing_u, spacing_v);
  const Eigen::Index supported = (roi_gap.array() <= 2.0 * spacing).count();
  result.mesh.vertices.positions = roi.FromRoi(grid_uvw);
  result.mesh.vertices.scalars["depth_mm"] = roi_depth;
  result.mesh.vertices.scalars["data_gap_mm"] = roi_gap;
  result.mesh.faces = GridFaces(grid);
  result.shape_vector = ToShapeVector(result.mesh.vertices.positions);
  result.max_data_gap_mm = roi_gap.maxCoeff();
  result.supported_fraction = static_cast<double>(supported) / static_cast<double>(m);
  result.fit_kind = options.fit.kind;
  stage.reset();
  return result;
}

std::string CrossSectionResult::BriefReport() const {
  std::ostringstream msg;
  msg << grid.lateral << "x" << grid.sternal << " grid from " << profiles_fitted << " profiles ("
      << ToString(fit_kind) << "), fit RMS " << fit_rms_mm << " mm, largest data gap " << max_data_gap_mm
      << " mm, " << vertices_inpainted << " vertices filled in 2D";
  return msg.str();
}

CrossSectionResult ResampleSurface(const TriangleMesh& surface, const LandmarkSet& landmarks,
                                   const ChestRoiOptions& roi_options, const CrossSectionOptions& options,
                                   const std::string& what) {
  const ChestRoi roi = ComputeChestRoi(landmarks, roi_options, what + " landmarks");
  return ResampleCrossSections(surface, roi, options, what);
}

}  // namespace pectus
