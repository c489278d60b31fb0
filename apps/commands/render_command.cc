// pectus render FILE -o picture.png: a picture of a mesh or cloud, optionally coloured by a per-vertex
// scalar on a fixed scale (so two files can be shown on one scale), with a colour bar.
#include <cmath>
#include <limits>

#include "apps/command.h"
#include "shape/core/error.h"
#include "shape/io/mesh_io.h"
#include "shape/render/colormap.h"
#include "shape/render/mesh_render.h"

namespace pectus::cli {
namespace {

class RenderCommand : public Command {
 public:
  std::string Name() const override { return "render"; }
  std::string Summary() const override {
    return "Draw a mesh or point cloud to a PNG, coloured by a scalar if asked";
  }
  std::string Example() const override {
    return "  pectus render surface.ply -o surface.png --view front\n"
           "  pectus render distance.ply -o distance.png --scalar distance_mm --range -5,5 --colormap "
           "diverging\n"
           "  pectus render ../shared/datasets/stanford_bunny/bun000.ply -o bun000.png --input-units m";
  }
  void Configure(CLI::App* app) override {
    app->add_option("file", input_, "PLY, OBJ, STL, PCD, XYZ or CSV file")->required();
    app->add_option("-o,--output", output_, "PNG to write")->required();
    app->add_option("--view", view_,
                    "front (look along -z, y up), side (along -x), back, top, or yaw,pitch in degrees")
        ->default_val("front");
    app->add_option("--size", size_, "Picture width and height in pixels")->default_val(800);
    app->add_option("--scalar", scalar_, "Colour by this per-vertex scalar (see `pectus info`)");
    app->add_option("--range", range_, "Fixed colour scale lo,hi for --scalar (default: the data's range)")
        ->delimiter(',')
        ->expected(2);
    app->add_option("--colormap", colormap_, "viridis, diverging or turbo")->default_val("viridis");
    app->add_option("--input-units", units_, "Unit of the file's coordinates: mm, cm, m, in")
        ->default_val("mm");
    app->add_option("--point-radius", point_radius_, "Pixels, for point clouds")->default_val(1);
  }
  std::vector<std::filesystem::path> Inputs() const override { return {input_}; }

  void Run(Context* context) override {
    if (std::filesystem::path(output_).extension() != ".png") ThrowUsage("render writes PNG: " + output_);
    const auto staged = StageOutput(context, *this, output_);
    ReadOptions options;
    options.input_units = ParseLengthUnit(units_);
    TriangleMesh mesh;
    {
      auto t = context->report.Stage("read");
      mesh = ReadMesh(input_, options);
    }
    if (mesh.num_vertices() == 0) ThrowBadInput(input_, "no points to draw");
    render::View view = ParseView();
    view.point_radius = point_radius_;
    Colors3 colors;
    const Colors3* colors_ptr = nullptr;
    render::Image bar;
    if (!scalar_.empty()) {
      const auto it = mesh.vertices.scalars.find(scalar_);
      if (it == mesh.vertices.scalars.end()) {
        std::string names;
        for (const auto& [name, v] : mesh.vertices.scalars) names += (names.empty() ? "" : ", ") + name;
        ThrowBadInput(input_, "no per-vertex scalar '" + scalar_ +
                                  "' (it has: " + (names.empty() ? "none" : names) + ")");
      }
      double lo = std::numeric_limits<double>::infinity(), hi = -lo;
      if (range_.size() == 2) {
        lo = range_[0];
        hi = range_[1];
        if (!(hi > lo)) ThrowUsage("--range needs lo < hi");
      } else {
        for (double v : it->second) {
          if (!std::isfinite(v)) continue;
          lo = std::min(lo, v);
          hi = std::max(hi, v);
        }
      }
      const render::Colormap map = ParseColormap();
      colors = render::MapColors(it->second, lo, hi, map);
      colors_ptr = &colors;
      bar = render::ColorBar(lo, hi, map, scalar_, size_);
      context->report["range"] = {lo, hi};
    }
    render::Image picture;
    {
      auto t = context->report.Stage("render");
      picture = mesh.num_faces() > 0 ? render::RenderMesh(mesh, view, colors_ptr)
                                     : render::RenderPoints(mesh.vertices, view, colors_ptr);
    }
    if (!bar.empty()) picture = render::HStack({picture, bar});
    render::WritePng(picture, staged);
    context->report["input"] = input_;
    context->report["output"] = output_;
    context->report["points"] = mesh.num_vertices();
    context->report["faces"] = mesh.num_faces();
  }

 private:
  render::View ParseView() const {
    if (view_ == "front") return render::View::Front(size_, size_);
    if (view_ == "side") return render::View::Side(size_, size_);
    if (view_ == "back") return render::View::Oblique(180, 0, size_, size_);
    if (view_ == "top") return render::View::Oblique(0, -90, size_, size_);
    const auto comma = view_.find(',');
    if (comma != std::string::npos) {
      try {
        return render::View::Oblique(std::stod(view_.substr(0, comma)), std::stod(view_.substr(comma + 1)),
                                     size_, size_);
      } catch (const std::exception&) {
      }
    }
    ThrowUsage("--view must be front, side, back, top or yaw,pitch in degrees, not '" + view_ + "'");
  }
  render::Colormap ParseColormap() const {
    if (colormap_ == "viridis") return render::Colormap::kViridis;
    if (colormap_ == "diverging") return render::Colormap::kDiverging;
    if (colormap_ == "turbo") return render::Colormap::kTurbo;
    ThrowUsage("--colormap must be viridis, diverging or turbo, not '" + colormap_ + "'");
  }

  std::string input_, output_, view_, scalar_, colormap_, units_;
  std::vector<double> range_;
  int size_ = 800;
  int point_radius_ = 1;
};

PECTUS_REGISTER_COMMAND(RenderCommand, 25);

}  // namespace
}  // namespace pectus::cli
