// pectus convert IN OUT: any format read to any format written, with units and an optional transform.
#include "apps/command.h"
#include "shape/core/error.h"
#include "shape/io/mesh_io.h"
#include "shape/io/transform_io.h"

namespace pectus::cli {
namespace {

class ConvertCommand : public Command {
 public:
  std::string Name() const override { return "convert"; }
  std::string Summary() const override {
    return "Convert between PLY, OBJ, STL, PCD, XYZ and CSV (units, transform)";
  }
  std::string Example() const override {
    return "  pectus convert ../shared/datasets/stanford_bunny/bun000.ply bun000_mm.ply --input-units m\n"
           "  pectus convert scan.stl scan.ply --transform T.json --ascii";
  }
  void Configure(CLI::App* app) override {
    app->add_option("input", input_, "File to read")->required();
    app->add_option("output", output_, "File to write; the format comes from the extension")->required();
    app->add_option("--input-units", units_, "Unit of the input's coordinates: mm, cm, m, in")
        ->default_val("mm");
    app->add_option("--transform", transform_,
                    "JSON with \"T_target_source\" (4x4, mm) applied after unit scaling");
    app->add_flag("--ascii", ascii_, "Write ASCII PLY/STL instead of binary");
  }
  std::vector<std::filesystem::path> Inputs() const override {
    std::vector<std::filesystem::path> in{input_};
    if (!transform_.empty()) in.push_back(transform_);
    return in;
  }

  void Run(Context* context) override {
    const auto staged = StageOutput(context, *this, output_);
    FormatFromPath(output_);  // an unknown output type is a usage error before any reading
    ReadOptions options;
    options.input_units = ParseLengthUnit(units_);
    TriangleMesh mesh;
    {
      auto t = context->report.Stage("read");
      mesh = ReadMesh(input_, options);
    }
    if (!transform_.empty()) {
      const Similarity3 T = ReadTransformJson(transform_);
      TransformInPlace(T, &mesh);
      context->report["transform"] = TransformToJson(T);
    }
    {
      auto t = context->report.Stage("write");
      WriteOptions w;
      w.binary = !ascii_;
      WriteMesh(staged, mesh, w);
    }
    context->report["input"] = input_;
    context->report["output"] = output_;
    context->report["points"] = mesh.num_vertices();
    context->report["faces"] = mesh.num_faces();
  }

 private:
  std::string input_, output_, units_, transform_;
  bool ascii_ = false;
};

PECTUS_REGISTER_COMMAND(ConvertCommand, 20);

}  // namespace

}  // namespace pectus::cli
