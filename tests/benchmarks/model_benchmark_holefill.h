// model_benchmark: hole filling on the pipeline's registered surfaces. Disks are removed from each surface
// (one inside the ROI over the sternum, one across its left border, one across its lower right corner),
// the holed surface is resampled, and its grid is compared inside the disks with (a) the resampling of
// the untouched surface and (b) the subject's true skin from the virtual scanner resampled on the same
// grid (model_benchmark_truth.h), the disk inside and the border disks apart.
#pragma once

#include <limits>
#include <string>
#include <vector>

#include "model_benchmark_holefill_regions.h"
#include "model_benchmark_truth.h"
#include "shape/io/landmark_io.h"
#include "shape/model/distance_map.h"
#include "shape/model/hole_fill_validation.h"
#include "shape/model/model_figures.h"

namespace pectus::bench {

/// One subject of the pipeline's output: its registered surface, ROI and true depths on the grid.
struct HoleFillSubject {
  std::string name;
  TriangleMesh surface;
  ChestRoi roi;
  TriangleMesh truth;  // the true skin in the pipeline's reference frame
  Eigen::VectorXd true_depth;
};

/// The errors over disks whose removed region is up to kMaxRegionMm across, those over the wider
/// ones apart, and each disk's region size (mm).
struct HoleFillMeasure {
  HoleFillErrors up_to_30_mm, wider;
  std::vector<double> region_mm;
};

inline HoleFillMeasure MeasureHoleFill(const HoleFillSubject& s, double diameter_mm,
                                       const CrossSectionOptions& options, HoleFillResult* out = nullptr) {
  const std::vector<RemovedDisk> disks = DefaultRemovedDisks(s.roi, diameter_mm / 2.0);
  const HoleFillResult h = ValidateHoleFill(s.surface, s.roi, disks, options, s.name);
  const Eigen::VectorXd& holed = h.holed.mesh.vertices.scalars.at("depth_mm");
  const Eigen::VectorXd& full = h.full.mesh.vertices.scalars.at("depth_mm");
  const Eigen::VectorXd scan_distance = ScanDataDistanceOnGrid(s.surface, h.full.mesh);
  const Eigen::VectorXd u = GridLateralPositions(s.roi, options.grid),
                        v = GridSternalPositions(s.roi, options.grid);
  HoleFillMeasure m;
  std::vector<int> disk_of;
  m.region_mm = RemovedRegionSizes(disks, options.grid, u, v, scan_distance, &disk_of);
  for (Eigen::Index k = 0; k < full.size(); ++k) {
    if (!h.in_disk[k] || disk_of[k] < 0) continue;
    const int p = disk_of[k] == 0 ? 0 : 1;  // inside, border
    HoleFillErrors& e = m.region_mm[disk_of[k]] <= kMaxRegionMm + 1e-9 ? m.up_to_30_mm : m.wider;
    e.vs_untouched[p].Add(holed[k] - full[k]);
    if (scan_distance[k] <= kScanHoleMm) {  // the untouched scan has data here
      e.vs_untouched_on_data[p].Add(holed[k] - full[k]);
      e.vs_truth_on_data[p].Add(holed[k] - s.true_depth[k]);
      e.untouched_vs_truth_on_data[p].Add(full[k] - s.true_depth[k]);
    }
    e.vs_truth[p].Add(holed[k] - s.true_depth[k]);
    e.untouched_vs_truth[p].Add(full[k] - s.true_depth[k]);
  }
  // The fill alone against the ground truth: the same disks removed from the true skin itself (no scan
  // error, so each region is its disk), resampled with the same options, against the true skin's grid.
  const HoleFillResult t = ValidateHoleFill(s.truth, s.roi, disks, options, s.name + " truth");
  HoleFillErrors& e = diameter_mm <= kMaxRegionMm + 1e-9 ? m.up_to_30_mm : m.wider;
  for (Eigen::Index k = 0; k < full.size(); ++k)
    if (t.in_disk[k] && disk_of[k] >= 0) e.true_skin[disk_of[k] == 0 ? 0 : 1].Add(t.error_mm[k]);
  if (out != nullptr) *out = h;
  return m;
}

inline std::vector<HoleFillSubject> LoadHoleFillSubjects(const std::filesystem::path& cohort,
                                                         const std::filesystem::path& out,
                                                         const nlohmann::json& report) {
  std::vector<HoleFillSubject> subjects;
  for (const nlohmann::json& s : report["subjects"]) {
    if (!s["ok"].get<bool>()) continue;
    HoleFillSubject h;
    h.name = s["name"];
    const std::filesystem::path dir = out / "subjects" / h.name;
    h.surface = ReadMesh(dir / "surface.ply");
    h.roi = ComputeChestRoi(ReadLandmarks(dir / "landmarks.mrk.json"));
    // The true skin is complete over the ROI: its resampling has no hole to fill.
    h.truth = TrueSurfaceInReferenceFrame(cohort, s);
    h.true_depth =
        ResampleCrossSections(h.truth, h.roi, {}, h.name + " truth").mesh.vertices.scalars.at("depth_mm");
    subjects.push_back(std::move(h));
  }
  return subjects;
}

/// Every figure of the hole-fill acceptance line and the choices behind it, as JSON rows.
inline nlohmann::json HoleFill(const std::filesystem::path& cohort, const std::filesystem::path& out,
                               const nlohmann::json& report, const std::filesystem::path& png) {
  const std::vector<HoleFillSubject> subjects = LoadHoleFillSubjects(cohort, out, report);
  nlohmann::json rows = nlohmann::json::array();
  auto run = [&](const std::string& name, const CrossSectionOptions& options, double diameter,
                 bool per_subject) {
    HoleFillErrors all, wider;
    nlohmann::json each = nlohmann::json::object();
    for (const HoleFillSubject& s : subjects) {
      const HoleFillMeasure m = MeasureHoleFill(s, diameter, options);
      const HoleFillErrors& e = m.up_to_30_mm;
      all.Add(e), wider.Add(m.wider);
      if (per_subject) {
        each[s.name] = {
            {"inside_vs_untouched_max_mm", e.vs_untouched[0].max},
            {"true_skin_inside_max_mm", e.true_skin[0].max},
            {"true_skin_border_max_mm", e.true_skin[1].max},
            {"inside_vs_untouched_on_data_max_mm", e.vs_untouched_on_data[0].max},
            {"inside_vs_truth_on_data_max_mm", e.vs_truth_on_data[0].max},
            {"inside_vs_truth_max_mm", e.vs_truth[0].max},
            {"border_vs_untouched_max_mm", e.vs_untouched[1].max},
            {"border_vs_truth_max_mm", e.vs_truth[1].max},
            {"untouched_vs_truth_max_mm", std::max(e.untouched_vs_truth[0].max, e.untouched_vs_truth[1].max)},
            {"removed_region_mm_inside_left_corner", m.region_mm}};
        if (m.wider.vs_untouched[0].count + m.wider.vs_untouched[1].count > 0)
          each[s.name]["wider_regions"] = m.wider.Json();
      }
    }
    nlohmann::json row = {{"fill", name}, {"diameter_mm", diameter}, {"subjects", subjects.size()}};
    row.update(all.Json());  // inside/border: the disks whose removed region is up to 30 mm
    row["wider_regions"] = wider.Json();
    if (per_subject) row["per_subject"] = each;
    std::cerr << row.dump() << "\n";
    rows.push_back(row);
  };
  // 1. The 2D fill's choices at 30 mm: against the 1D profiles alone, order, border, stretch, gap.
  auto with = [](GridHoleFill mode, int order, double stretch, double gap) {
    CrossSectionOptions o;
    o.holes.mode = mode;
    o.holes.inpainting.order = order;
    o.holes.inpainting.stretch = stretch;
    o.holes.gap_mm = gap;
    return o;
  };
  const CrossSectionOptions defaults;
  run("profiles only (1D row/column blend)", with(GridHoleFill::kProfiles, 2, 1.0, 3.0), 30.0, true);
  // Border holes: the ROI's grid alone (no grown grid: they reach its border and keep the profiles), and
  // the stretch everywhere rather than about the sternal line only.
  CrossSectionOptions roi_grid_only, stretch_everywhere;
  roi_grid_only.extend_grid = false;
  stretch_everywhere.holes.inpainting.stretch_band_mm = std::numeric_limits<double>::infinity();
  run("default on the ROI's grid only", roi_grid_only, 30.0, true);
  run("default with the stretch everywhere", stretch_everywhere, 30.0, false);
  struct Variant {
    GridHoleFill mode;
    int order;
    double stretch, gap;
  };
  for (const Variant& v : std::vector<Variant>{{GridHoleFill::kInpaint, 2, 1.0, 3.0},
                                               {GridHoleFill::kInpaint, 2, 3.0, 3.0},
                                               {GridHoleFill::kInpaint, 3, 2.0, 3.0},
                                               {GridHoleFill::kInpaintInside, 2, 1.0, 3.0},
                                               {GridHoleFill::kInpaintInside, 2, 2.0, 3.0},
                                               {GridHoleFill::kInpaintInside, 2, 5.0, 3.0},
                                               {GridHoleFill::kInpaintInside, 3, 3.0, 3.0},
                                               {GridHoleFill::kInpaintInside, 2, 3.0, 2.0},
                                               {GridHoleFill::kInpaintInside, 2, 3.0, 5.0}}) {
    run(ToString(v.mode) + ", order " + std::to_string(v.order) + ", stretch " +
            std::to_string(v.stretch).substr(0, 3) + ", gap " + std::to_string(v.gap).substr(0, 3) + " mm",
        with(v.mode, v.order, v.stretch, v.gap), 30.0, false);
  }
  // 2. The profile curve: each fit's 30 mm hole filling, and its whole grid against the true surface.
  struct Fit {
    std::string name;
    ProfileFitOptions options;
  };
  std::vector<Fit> fits;
  for (int q : {3, 2}) {
    ProfileFitOptions o;
    o.penalty_order = q;
    fits.push_back({"spline (penalty order " + std::to_string(q) + ")", o});
  }
  for (int d : {4, 6, 8, 10}) {
    ProfileFitOptions o;
    o.kind = ProfileFitKind::kPolynomial;
    o.polynomial_degree = d;
    fits.push_back({"polynomial degree " + std::to_string(d), o});
  }
  for (const Fit& fit : fits) {
    CrossSectionOptions options;
    options.fit = fit.options;
    HoleFillErrors all;
    ErrorStats grid_to_truth;
    for (const HoleFillSubject& s : subjects) {
      HoleFillResult h;
      all.Add(MeasureHoleFill(s, 30.0, options, &h).up_to_30_mm);
      const Eigen::VectorXd& full = h.full.mesh.vertices.scalars.at("depth_mm");
      for (Eigen::Index k = 0; k < full.size(); ++k) grid_to_truth.Add(full[k] - s.true_depth[k]);
    }
    nlohmann::json row = {
        {"profile_curve", fit.name},
        {"max_error_in_30_mm_holes_vs_untouched_mm",
         std::max(all.vs_untouched[0].max, all.vs_untouched[1].max)},
        {"max_error_in_30_mm_holes_vs_truth_mm", std::max(all.vs_truth[0].max, all.vs_truth[1].max)},
        {"grid_to_truth_rms_mm", grid_to_truth.rms()},
        {"grid_to_truth_max_mm", grid_to_truth.max}};
    std::cerr << row.dump() << "\n";
    rows.push_back(row);
  }
  // 3. The default against the size of the removed regions.
  for (double diameter : {10.0, 20.0, 30.0, 40.0}) run("default", defaults, diameter, true);
  if (!png.empty() && !subjects.empty()) {
    HoleFillResult h;
    MeasureHoleFill(subjects[0], 30.0, defaults, &h);
    SurfaceMapFigure f;
    f.title = subjects[0].name + ": hole-fill error (holed - untouched), 3 disks of 30 mm";
    f.min = -0.5;
    f.max = 0.5;
    f.up = -subjects[0].roi.sternal;
    WriteSurfaceMapPng(png, h.holed.mesh, h.error_mm, subjects[0].roi.normal, f);
  }
  return rows;
}

}  // namespace pectus::bench
