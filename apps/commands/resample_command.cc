// pectus resample SURFACE --landmarks L.mrk.json -o GRID.ply: a registered chest surface resampled by
// cross-sections on the landmark-bounded grid (its shape vector); --validate removes regions of the scan
// and reports how well the resampling rebuilds them.
#include <fstream>
#include <sstream>

#include "apps/command.h"
#include "shape/core/error.h"
#include "shape/core/log.h"
#include "shape/io/landmark_io.h"
#include "shape/io/mesh_io.h"
#include "shape/model/cross_section_resampler.h"
#include "shape/model/hole_fill_validation.h"
#ifdef PECTUS_HAVE_RENDER
#include "shape/model/model_figures.h"
#endif

namespace pectus::cli {
namespace {

// "a,b,c" -> three numbers; throws Error(kUsage) naming the option otherwise.
Eigen::Vector3d ParseTriple(const std::string& text, const std::string& option) {
  std::stringstream in(text);
  Eigen::Vector3d v;
  char comma1 = 0, comma2 = 0;
  if (!(in >> v.x() >> comma1 >> v.y() >> comma2 >> v.z()) || comma1 != ',' || comma2 != ',' ||
      !v.allFinite()) {
    ThrowUsage(option + " '" + text + "' is not three numbers a,b,c");
  }
  return v;
}

class ResampleCommand : public Command {
 public:
  std::string Name() const override { return "resample"; }
  std::string Summary() const override {
    return "Resample a registered chest surface on the landmark-bounded grid (shape vector); validate hole "
           "filling";
  }
  std::string Example() const override {
    return "  pectus resample subject01.ply --landmarks subject01.mrk.json -o subject01_grid.ply --vector "
           "s01.csv\n"
           "  pectus resample scan.ply --landmarks scan.mrk.json --validate --hole-radius 15 \\\n"
           "      --error-png holes.png --error-ply holes.ply --report holes.json\n"
           "  (ROI: notch to xiphoid along the sternum, the first left costal cartilage and its mirror "
           "across;\n"
           "   grid vertices row by row from the notch, 51 across by 101 along by default)";
  }
  void Configure(CLI::App* app) override {
    app->add_option("surface", input_, "Registered surface (mesh or point cloud), mm")->required();
    app->add_option("--landmarks", landmarks_, "Landmarks of the surface (.mrk.json, .fcsv, .csv)")
        ->required();
    app->add_option("-o,--output", output_, "Resampled grid mesh (vertex k = row * lateral + column)");
    app->add_option("--vector", vector_, "Shape vector as CSV: one line x,y,z per grid vertex");
    app->add_option("--grid", grid_, "Grid vertices LATERALxSTERNAL")->default_val("51x101");
    app->add_option("--fit", fit_, "Profile curve: spline (P-spline) or polynomial")->default_val("spline");
    app->add_option("--degree", options_.fit.polynomial_degree, "Polynomial degree")->default_val(8);
    app->add_option("--knot-spacing", options_.fit.knot_spacing_mm, "Spline knot spacing, mm")
        ->default_val(5.0);
    app->add_option("--smoothing", options_.fit.smoothing, "Spline roughness penalty weight")
        ->default_val(1e-3);
    app->add_option("--sections", sections_, "Section planes: rows, columns or both")->default_val("both");
    app->add_option("--hole-fill", hole_fill_,
                    "Holes: inpaint (2D), inpaint-inside (2D, but profiles where the scan ends) or profiles")
        ->default_val("inpaint-inside");
    app->add_option("--inpaint-order", options_.holes.inpainting.order, "2D fill: derivative order, 2 or 3")
        ->default_val(options_.holes.inpainting.order);
    app->add_option("--inpaint-stretch", options_.holes.inpainting.stretch,
                    "2D fill: lateral stretch (> 1 follows the sternal direction more)")
        ->default_val(options_.holes.inpainting.stretch);
    app->add_option("--inpaint-band", options_.holes.inpainting.stretch_band_mm,
                    "2D fill: the stretch applies within this distance of the sternal line, mm")
        ->default_val(options_.holes.inpainting.stretch_band_mm);
    app->add_flag("!--roi-grid-only", options_.extend_grid,
                  "Sample and fill on the ROI's grid only (default: grown by the fit margin, so holes "
                  "across the ROI's border are filled in 2D where the data go on)");
    app->add_option("--fit-margin", options_.fit_margin_mm, "Profile data used beyond the ROI, mm")
        ->default_val(25.0);
    app->add_option("--notch-label", roi_.notch_label, "Label of the sternal notch")
        ->default_val(roi_.notch_label);
    app->add_option("--xiphoid-label", roi_.xiphoid_label, "Label of the xiphoid")
        ->default_val(roi_.xiphoid_label);
    app->add_option("--cartilage-label", roi_.cartilage_label, "Label of the first left costal cartilage")
        ->default_val(roi_.cartilage_label);
    app->add_option("--superior-margin", roi_.superior_margin_mm, "ROI beyond the notch, mm")
        ->default_val(0.0);
    app->add_option("--inferior-margin", roi_.inferior_margin_mm, "ROI beyond the xiphoid, mm")
        ->default_val(0.0);
    app->add_option("--lateral-margin", roi_.lateral_margin_mm, "ROI beyond the cartilage and its mirror, mm")
        ->default_val(0.0);
    app->add_option("--anterior", anterior_,
                    "Anterior direction x,y,z: levels the lateral axis (default: the "
                    "plane through the three landmarks)");
    app->add_option("--input-units", units_, "Unit of the surface and landmark coordinates: mm, cm, m, in")
        ->default_val("mm");
    app->add_flag("--validate", validate_, "Hole-fill validation: remove regions, resample, compare");
    app->add_option("--hole-radius", hole_radius_, "--validate: radius of the default regions, mm")
        ->default_val(15.0);
    app->add_option("--hole", holes_, "--validate: a region U,V,R in ROI coordinates (mm), repeatable");
    app->add_option("--error-png", error_png_, "--validate: colour map of the error on the grid");
    app->add_option("--error-ply", error_ply_, "--validate: grid with the error as scalar and colours");
    app->add_option("--error-range", error_range_, "--validate: colour scale of the error, +-mm")
        ->default_val(1.0);
  }
  std::vector<std::filesystem::path> Inputs() const override { return {input_, landmarks_}; }

  void Run(Context* context) override {
    if (!validate_ && output_.empty() && vector_.empty())
      ThrowUsage("give -o/--output and/or --vector (or --validate)");
    if (!validate_ && (!error_png_.empty() || !error_ply_.empty()))
      ThrowUsage("--error-png/--error-ply need --validate");
    options_.grid = ParseGridSize(grid_);
    options_.fit.kind = ParseProfileFitKind(fit_);
    options_.directions = ParseSectionDirections(sections_);
    options_.holes.mode = ParseGridHoleFill(hole_fill_);
    if (!anterior_.empty()) roi_.anterior_hint = ParseTriple(anterior_, "--anterior");
    std::string why;
    if (!options_.IsValid(&why) || !roi_.IsValid(&why)) ThrowUsage(why);
#ifndef PECTUS_HAVE_RENDER
    if (!error_png_.empty()) ThrowUsage("--error-png needs pectus built with pectus::render");
#endif
    std::filesystem::path out, vec, png, ply;
    if (!output_.empty()) out = StageOutput(context, *this, output_);
    if (!vector_.empty()) vec = StageOutput(context, *this, vector_);
    if (!error_png_.empty()) png = StageOutput(context, *this, error_png_);
    if (!error_ply_.empty()) ply = StageOutput(context, *this, error_ply_);

    // 1. Read the surface and its landmarks.
    ReadOptions read;
    read.input_units = ParseLengthUnit(units_);
    TriangleMesh surface;
    LandmarkSet landmarks;
    {
      auto t = context->report.Stage("read");
      surface = ReadMesh(input_, read);
      landmarks = ReadLandmarks(landmarks_, LandmarkReadOptions{read.input_units});
    }
    // 2. The ROI from the landmarks.
    const ChestRoi roi = ComputeChestRoi(landmarks, roi_, landmarks_);
    context->report["roi"] = roi.ToJson();
    context->report["grid"] = {{"lateral", options_.grid.lateral}, {"sternal", options_.grid.sternal}};
    context->report["fit"] = {{"kind", ToString(options_.fit.kind)},
                              {"sections", ToString(options_.directions)},
                              {"hole_fill", ToString(options_.holes.mode)},
                              {"inpaint_order", options_.holes.inpainting.order},
                              {"inpaint_stretch", options_.holes.inpainting.stretch},
                              {"inpaint_band_mm", options_.holes.inpainting.stretch_band_mm},
                              {"extend_grid", options_.extend_grid}};

    // 3. Resample (or validate).
    CrossSectionResult result;
    if (validate_) {
      std::vector<RemovedDisk> disks;
      for (const std::string& h : holes_) {
        const Eigen::Vector3d d = ParseTriple(h, "--hole");
        disks.push_back({d.x(), d.y(), d.z()});
      }
      if (disks.empty()) disks = DefaultRemovedDisks(roi, hole_radius_);
      HoleFillResult v;
      {
        auto t = context->report.Stage("validate");
        v = ValidateHoleFill(surface, roi, disks, options_, input_);
      }
      nlohmann::json regions = nlohmann::json::array();
      for (const RemovedDisk& d : disks)
        regions.push_back({{"u_mm", d.u}, {"v_mm", d.v}, {"radius_mm", d.radius_mm}});
      context->report["hole_fill"] = {{"regions", regions},
                                      {"vertices_in_regions", v.vertices_in_disks},
                                      {"max_error_in_regions_mm", v.max_error_in_disks_mm},
                                      {"rms_error_in_regions_mm", v.rms_error_in_disks_mm},
                                      {"max_error_mm", v.max_error_mm},
                                      {"rms_error_mm", v.rms_error_mm},
                                      {"message", v.message}};
      Info(v.message);
      TriangleMesh error_mesh = v.holed.mesh;
      error_mesh.vertices.scalars["error_mm"] = v.error_mm;
      error_mesh.vertices.scalars["in_region"] = v.in_disk.cast<double>();
#ifdef PECTUS_HAVE_RENDER
      error_mesh.vertices.colors = ColorsForValues(v.error_mm, -error_range_, error_range_);
      if (!png.empty()) {
        SurfaceMapFigure figure;
        figure.title = "hole-fill error (holed - untouched), mm";
        figure.min = -error_range_;
        figure.max = error_range_;
        WriteSurfaceMapPng(png, error_mesh, v.error_mm, roi.normal, figure);
      }
#endif
      if (!ply.empty()) WriteMesh(ply, error_mesh);
      result = v.holed;
    } else {
      auto t = context->report.Stage("resample");
      result = ResampleCrossSections(surface, roi, options_, input_);
    }
    Info(result.BriefReport());
    context->report["profiles_fitted"] = result.profiles_fitted;
    context->report["profiles_unfitted"] = result.profiles_unfitted;
    context->report["profile_points"] = result.profile_points;
    context->report["fit_rms_mm"] = result.fit_rms_mm;
    context->report["max_data_gap_mm"] = result.max_data_gap_mm;
    context->report["supported_fraction"] = result.supported_fraction;
    context->report["vertices_inpainted"] = result.vertices_inpainted;
    context->report["shape_vector_size"] = result.shape_vector.size();

    // 4. Write the grid and the shape vector.
    auto t = context->report.Stage("write");
    if (!out.empty()) {
      WriteOptions w;
      w.comment = "pectus resample: " + std::to_string(options_.grid.lateral) + "x" +
                  std::to_string(options_.grid.sternal) + " grid, vertex = row * lateral + column";
      WriteMesh(out, result.mesh, w);
    }
    if (!vec.empty()) {
      std::ostringstream csv;
      csv.precision(10);
      csv << "x,y,z\n";
      const Points3& p = result.mesh.vertices.positions;
      for (Eigen::Index k = 0; k < p.rows(); ++k) csv << p(k, 0) << ',' << p(k, 1) << ',' << p(k, 2) << '\n';
      WriteFileAtomically(vec, csv.str());
    }
    context->report["input"] = input_;
    context->report["output"] = output_;
  }

 private:
  std::string input_, landmarks_, output_, vector_, grid_, fit_, sections_, anterior_, units_, hole_fill_;
  std::string error_png_, error_ply_;
  std::vector<std::string> holes_;
  bool validate_ = false;
  double hole_radius_ = 15.0, error_range_ = 1.0;
  CrossSectionOptions options_;
  ChestRoiOptions roi_;
};

PECTUS_REGISTER_COMMAND(ResampleCommand, 80);

}  // namespace
}  // namespace pectus::cli
