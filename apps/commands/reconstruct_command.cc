// pectus reconstruct: a surface from a point cloud (oriented normals, partition-of-unity RBF implicit,
// marching cubes, holes filled up to a size, trimmed to the scanned region), checked with CGAL.
#include <sstream>

#include "apps/command.h"
#include "shape/core/error.h"
#include "shape/core/log.h"
#include "shape/io/mesh_io.h"
#include "shape/surface/reconstruct_surface.h"

namespace pectus::cli {
namespace {
namespace fs = std::filesystem;

class ReconstructCommand : public Command {
 public:
  std::string Name() const override { return "reconstruct"; }
  std::string Summary() const override {
    return "Surface from a point cloud: RBF implicit with holes filled, trimmed to the data (PLY/STL/OBJ)";
  }
  std::string Example() const override {
    return "  pectus reconstruct merged.ply -o surface.ply --spacing 1.0 --fill-holes 30 --report r.json\n"
           "  pectus reconstruct scan.xyz --input-units m -o surface.stl --target-faces 100000\n"
           "  pectus reconstruct chest.ply -o chest.obj --viewpoint 0,0,600 --smoothing 0.01";
  }
  void Configure(CLI::App* app) override {
    app->add_option("cloud", input_, "Point cloud (PLY, OBJ, STL, PCD, XYZ/CSV); normals are used if present")
        ->required();
    app->add_option("-o,--output", output_,
                    "Surface mesh: .ply (with normals and data distance), .stl or .obj")
        ->required();
    app->add_option("--input-units", units_, "Unit of the cloud: mm, cm, m, in")->default_val("mm");
    app->add_option("--spacing", options_.spacing_mm,
                    "Grid step of the isosurface (mm); 0 = 1.5 x point spacing")
        ->default_val(0.0)
        ->check(CLI::NonNegativeNumber);
    app->add_option("--target-faces", options_.target_faces,
                    "With --spacing 0: choose the step for about this many triangles")
        ->default_val(0)
        ->check(CLI::NonNegativeNumber);
    app->add_option("--detail", options_.detail_mm,
                    "Spacing of the RBF centres (mm), the finest detail kept; 0 = automatic")
        ->default_val(0.0)
        ->check(CLI::NonNegativeNumber);
    app->add_option("--smoothing", options_.smoothing,
                    "Bending-energy weight of the local fits; larger = smoother")
        ->default_val(options_.smoothing)
        ->check(CLI::NonNegativeNumber);
    app->add_option("--fill-holes", options_.fill_holes_mm, "Fill holes up to this width (mm); 0 = none")
        ->default_val(options_.fill_holes_mm)
        ->check(CLI::NonNegativeNumber);
    app->add_option("--margin", options_.margin_mm,
                    "Keep surface this far (mm) beyond the data; 0 = automatic")
        ->default_val(0.0)
        ->check(CLI::NonNegativeNumber);
    app->add_option("--normal-neighbours", options_.normal_neighbours, "Neighbours per point for PCA normals")
        ->default_val(options_.normal_neighbours)
        ->check(CLI::Range(3, 256));
    app->add_flag("--recompute-normals", options_.recompute_normals,
                  "Estimate normals even if the cloud has them");
    app->add_option("--viewpoint", viewpoint_,
                    "Orient normals toward this scanner position x,y,z (mm) instead of by propagation")
        ->delimiter(',')
        ->expected(3);
    app->add_flag("--no-check", no_check_, "Skip the CGAL check (manifold, self-intersections)");
  }
  std::vector<fs::path> Inputs() const override { return {input_}; }

  void Run(Context* context) override {
    const auto staged = StageOutput(context, *this, output_);
    const FileFormat format = FormatFromPath(output_);
    if (format != FileFormat::kPly && format != FileFormat::kStl && format != FileFormat::kObj) {
      ThrowUsage("--output must end in .ply, .stl or .obj: " + output_);
    }
    options_.check = !no_check_;
    if (!viewpoint_.empty())
      options_.viewpoint = Eigen::Vector3d(viewpoint_[0], viewpoint_[1], viewpoint_[2]);

    PointCloud cloud;
    {
      auto t = context->report.Stage("read");
      ReadOptions ro;
      ro.input_units = ParseLengthUnit(units_);
      cloud = ReadPointCloud(input_, ro);
    }
    ReconstructResult result;
    {
      auto t = context->report.Stage("reconstruct");
      result = ReconstructSurface(cloud, options_, input_);
    }
    context->report.AddTimes(result.timings_s);
    if (result.check && (!result.check->manifold || result.check->self_intersecting)) {
      ThrowFailure("reconstruct: the surface failed the CGAL check (" + result.check->message + ")", input_);
    }
    {
      auto t = context->report.Stage("write");
      WriteMesh(staged, result.mesh);
    }

    auto& r = context->report.json();
    r["input"] = input_;
    r["output"] = output_;
    r["input_points"] = result.input_points;
    r["working_points"] = result.working_points;
    r["used_points"] = result.used_points;
    r["normals"] = result.normals_source;
    r["vertices"] = result.mesh.num_vertices();
    r["faces"] = result.mesh.num_faces();
    // Carr et al.'s fitting accuracy (dissertation Eq. 11): the largest residual over every constraint.
    r["fitting"] = {{"carr_max_residual_mm", result.accuracy.fitting_accuracy_mm},
                    {"on_surface_max_mm", result.accuracy.on_surface_max_mm},
                    {"on_surface_rms_mm", result.accuracy.on_surface_rms_mm},
                    {"on_surface_p95_mm", result.accuracy.on_surface_p95_mm},
                    {"off_surface_max_mm", result.accuracy.off_surface_max_mm},
                    {"constraints", result.accuracy.num_on_surface + result.accuracy.num_off_surface}};
    r["scales_mm"] = {{"point_spacing", result.point_spacing_mm},
                      {"noise", result.noise_mm},
                      {"grid_spacing", result.spacing_mm},
                      {"centre_spacing", result.centre_spacing_mm},
                      {"cell_size", result.cell_size_mm}};
    r["local_fits"] = result.cells;
    r["holes"] = {{"filled", result.trim.holes_filled},
                  {"largest_filled_mm", result.trim.largest_hole_filled_mm},
                  {"left_open", result.trim.holes_left_open},
                  {"fill_limit_mm", options_.fill_holes_mm}};
    r["border_edges"] = result.trim.boundary_edges;
    r["watertight"] = result.trim.boundary_edges == 0;
    if (result.check) {
      r["check"] = {{"manifold", result.check->manifold},
                    {"self_intersecting", result.check->self_intersecting},
                    {"closed", result.check->closed},
                    {"components", result.check->components},
                    {"area_mm2", result.check->area_mm2}};
    }
    r["message"] = result.message;
    Info(result.BriefReport());
  }

 private:
  std::string input_, output_, units_;
  std::vector<double> viewpoint_;
  bool no_check_ = false;
  ReconstructOptions options_;
};

PECTUS_REGISTER_COMMAND(ReconstructCommand, 65);

}  // namespace
}  // namespace pectus::cli
