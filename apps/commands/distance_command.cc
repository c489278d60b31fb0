// pectus distance SURFACE REFERENCE: distance map of a surface to a reference (nearest point or signed
// point-to-surface), statistics, colour maps on a fixed scale, histogram, coloured PLY; growth compensation
// for pre/post comparisons; pectus measures of the surface.
#include <sstream>

#include "apps/command.h"
#include "shape/core/error.h"
#include "shape/core/log.h"
#include "shape/io/landmark_io.h"
#include "shape/io/mesh_io.h"
#include "shape/model/compute_chest_roi.h"
#include "shape/model/distance_map.h"
#include "shape/model/growth_compensation.h"
#include "shape/model/measure_chest.h"
#ifdef PECTUS_HAVE_RENDER
#include "shape/model/model_figures.h"
#endif

namespace pectus::cli {
namespace {

class DistanceCommand : public Command {
 public:
  std::string Name() const override { return "distance"; }
  std::string Summary() const override {
    return "Distance map of a surface to a reference: statistics, colour map, histogram, coloured PLY, "
           "measures";
  }
  std::string Example() const override {
    return "  pectus distance subject01_grid.ply mean.ply --png s01.png --range 10 --histogram s01_hist.png "
           "\\\n"
           "      --ply s01_colored.ply --report s01.json\n"
           "  pectus distance post.ply pre.ply --surface-landmarks post.mrk.json --reference-landmarks "
           "pre.mrk.json \\\n"
           "      --measures --png change.png --range 15   (growth scale estimated from the landmarks)\n"
           "  (signed distances are positive where the surface lies in front of the reference, along its "
           "normals)";
  }
  void Configure(CLI::App* app) override {
    app->add_option("surface", surface_, "Surface the map is shown on (its vertices are measured), mm")
        ->required();
    app->add_option("reference", reference_, "Reference surface (a mesh for signed distances), mm")
        ->required();
    app->add_option("--kind", kind_, "signed (point to surface) or nearest (nearest vertex)")
        ->default_val("signed");
    app->add_option("--png", png_, "Colour map of the distances rendered on the surface");
    app->add_option("--range", range_,
                    "Colour scale: +-R mm for signed, [0, R] for nearest (0: from the data)")
        ->default_val(0.0);
    app->add_option("--histogram", histogram_, "Histogram of the distances (PNG)");
    app->add_option("--ply", ply_, "The surface with a 'distance_mm' scalar and colours");
    app->add_option("--csv", csv_, "Distances as CSV: x,y,z,distance_mm per surface vertex");
    app->add_option("--surface-landmarks", surface_landmarks_, "Landmarks of the surface (growth, measures)");
    app->add_option("--reference-landmarks", reference_landmarks_, "Landmarks of the reference (growth)");
    app->add_option("--growth-scale", growth_scale_,
                    "Known growth scale (surface size / reference size); the "
                    "reference is scaled before measuring (0: none, or "
                    "estimated when both landmark files are given)")
        ->default_val(0.0);
    app->add_flag("--measures", measures_,
                  "Depression depth and external indices of the surface (needs "
                  "--surface-landmarks)");
    app->add_option("--input-units", units_, "Unit of the coordinates of all inputs: mm, cm, m, in")
        ->default_val("mm");
  }
  std::vector<std::filesystem::path> Inputs() const override {
    std::vector<std::filesystem::path> in{surface_, reference_};
    if (!surface_landmarks_.empty()) in.push_back(surface_landmarks_);
    if (!reference_landmarks_.empty()) in.push_back(reference_landmarks_);
    return in;
  }

  void Run(Context* context) override {
    const DistanceKind kind = ParseDistanceKind(kind_);
    if (!(range_ >= 0.0)) ThrowUsage("--range must be >= 0 mm");
    if (!(growth_scale_ >= 0.0)) ThrowUsage("--growth-scale must be > 0 (or 0 for none)");
    if (measures_ && surface_landmarks_.empty()) ThrowUsage("--measures needs --surface-landmarks");
    if (reference_landmarks_.empty() != surface_landmarks_.empty() && growth_scale_ == 0.0 && !measures_) {
      ThrowUsage(
          "growth compensation from landmarks needs both --surface-landmarks and --reference-landmarks");
    }
#ifndef PECTUS_HAVE_RENDER
    if (!png_.empty() || !histogram_.empty())
      ThrowUsage("--png/--histogram need pectus built with pectus::render");
#endif
    auto stage = [&](const std::string& p) {
      return p.empty() ? std::filesystem::path() : StageOutput(context, *this, p);
    };
    const auto png = stage(png_), histogram = stage(histogram_), ply = stage(ply_), csv = stage(csv_);

    // 1. Read.
    ReadOptions read;
    read.input_units = ParseLengthUnit(units_);
    TriangleMesh surface, reference;
    LandmarkSet surface_landmarks, reference_landmarks;
    {
      auto t = context->report.Stage("read");
      surface = ReadMesh(surface_, read);
      reference = ReadMesh(reference_, read);
      if (!surface_landmarks_.empty())
        surface_landmarks = ReadLandmarks(surface_landmarks_, {read.input_units});
      if (!reference_landmarks_.empty())
        reference_landmarks = ReadLandmarks(reference_landmarks_, {read.input_units});
    }

    // 2. Growth compensation: the reference is brought to the surface's frame and size.
    if (!reference_landmarks_.empty() && !surface_landmarks_.empty()) {
      GrowthCompensationOptions g;
      g.scale = growth_scale_;
      const GrowthCompensationResult r = CompensateGrowth(reference_landmarks, surface_landmarks, g,
                                                          reference_landmarks_, surface_landmarks_);
      TransformInPlace(r.T_post_pre, &reference);
      context->report["growth"] = {{"scale", r.scale},
                                   {"estimated", r.estimated},
                                   {"landmark_rms_mm", r.rms_mm},
                                   {"labels", r.labels},
                                   {"message", r.message}};
      Info(r.message);
    } else if (growth_scale_ > 0.0) {
      const Eigen::Vector3d centre = reference.vertices.positions.colwise().mean().transpose();
      TransformInPlace(ScaleAbout(centre, growth_scale_), &reference);
      context->report["growth"] = {
          {"scale", growth_scale_}, {"estimated", false}, {"about", "reference centroid"}};
    }

    // 3. The distance map and its statistics.
    DistanceMapResult map;
    {
      auto t = context->report.Stage("distance");
      map = ComputeDistanceMap(surface.vertices.positions, reference, kind, reference_);
    }
    Info(map.message);
    context->report["kind"] = ToString(kind);
    context->report["statistics"] = map.stats.ToJson();
    const double range = range_ > 0.0 ? range_ : std::max(1e-6, map.stats.max_abs);
    const double lo = kind == DistanceKind::kSignedSurface ? -range : 0.0;
    context->report["colour_scale_mm"] = {lo, range};

    // 4. Measures of the surface.
    if (measures_) {
      auto t = context->report.Stage("measures");
      const ChestRoi roi = ComputeChestRoi(surface_landmarks, {}, surface_landmarks_);
      const ChestMeasures m = MeasureChest(surface, roi, {}, surface_);
      context->report["measures"] = m.ToJson();
      Info(m.message);
    }

    // 5. Outputs.
    auto t = context->report.Stage("write");
    TriangleMesh colored = surface;
    colored.vertices.scalars["distance_mm"] = map.distances;
#ifdef PECTUS_HAVE_RENDER
    colored.vertices.colors = ColorsForValues(map.distances, lo, range);
    const Eigen::Vector3d view = surface_landmarks_.empty()
                                     ? Eigen::Vector3d::Zero()
                                     : ComputeChestRoi(surface_landmarks, {}, surface_landmarks_).normal;
    if (!png.empty()) {
      SurfaceMapFigure figure;
      figure.title =
          (kind == DistanceKind::kSignedSurface ? "signed distance to " : "nearest-point distance to ") +
          std::filesystem::path(reference_).filename().string() + ", mm";
      figure.min = lo;
      figure.max = range;
      WriteSurfaceMapPng(png, colored, map.distances, view, figure);
    }
    if (!histogram.empty()) WriteHistogramPng(histogram, map.distances, "distance, mm", lo, range);
#endif
    if (!ply.empty()) WriteMesh(ply, colored);
    if (!csv.empty()) {
      std::ostringstream out;
      out.precision(10);
      out << "x,y,z,distance_mm\n";
      const Points3& p = surface.vertices.positions;
      for (Eigen::Index k = 0; k < p.rows(); ++k) {
        out << p(k, 0) << ',' << p(k, 1) << ',' << p(k, 2) << ',' << map.distances[k] << '\n';
      }
      WriteFileAtomically(csv, out.str());
    }
    context->report["surface"] = surface_;
    context->report["reference"] = reference_;
  }

 private:
  std::string surface_, reference_, kind_, png_, histogram_, ply_, csv_, units_;
  std::string surface_landmarks_, reference_landmarks_;
  double range_ = 0.0, growth_scale_ = 0.0;
  bool measures_ = false;
};

PECTUS_REGISTER_COMMAND(DistanceCommand, 100);

}  // namespace
}  // namespace pectus::cli
