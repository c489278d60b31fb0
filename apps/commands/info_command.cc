// pectus info FILE: what a geometry, landmark or pose file holds.
#include <cstdio>

#include "apps/command.h"
#include "shape/core/log.h"
#include "shape/io/mesh_io.h"

namespace pectus::cli {
namespace {

class InfoCommand : public Command {
 public:
  std::string Name() const override { return "info"; }
  std::string Summary() const override {
    return "Show what a geometry file holds: elements, properties, bounds, likely units";
  }
  std::string Example() const override {
    return "  pectus info ../shared/datasets/stanford_bunny/bun000.ply --report r.json\n"
           "  (the report carries \"points\": 40256, \"faces\", \"elements\", \"bounds\", \"likely_units\")";
  }
  void Configure(CLI::App* app) override {
    app->add_option("file", file_, "PLY, OBJ, STL, PCD, XYZ or CSV file")->required();
  }
  std::vector<std::filesystem::path> Inputs() const override { return {file_}; }

  void Run(Context* context) override {
    FileSummary summary;
    ReadOptions options;
    options.warn_units = false;  // info reports the likely unit itself
    TriangleMesh mesh;
    {
      auto t = context->report.Stage("read");
      mesh = ReadMesh(file_, options, &summary);
    }
    const Bounds3 b = ComputeBounds(mesh.vertices.positions);
    const auto unit = GuessLengthUnit(b);
    auto& r = context->report.json();
    r["file"] = file_;
    r["format"] = summary.format;
    r["encoding"] = summary.encoding;
    r["points"] = mesh.num_vertices();
    r["faces"] = mesh.num_faces();
    r["has_normals"] = mesh.vertices.has_normals();
    r["has_colors"] = mesh.vertices.has_colors();
    std::vector<std::string> scalar_names;
    for (const auto& [name, values] : mesh.vertices.scalars) scalar_names.push_back(name);
    r["scalars"] = scalar_names;
    nlohmann::json elements = nlohmann::json::array();
    for (const auto& e : summary.elements) {
      elements.push_back({{"name", e.name}, {"count", e.count}, {"properties", e.properties}});
    }
    r["elements"] = elements;
    if (!b.empty()) {
      r["bounds"] = {{"min", {b.min.x(), b.min.y(), b.min.z()}},
                     {"max", {b.max.x(), b.max.y(), b.max.z()}},
                     {"extent", {b.extent().x(), b.extent().y(), b.extent().z()}}};
    }
    r["likely_units"] = unit ? ToString(*unit) : "unknown";

    std::printf("%s\n  format    %s %s\n", file_.c_str(), summary.format.c_str(), summary.encoding.c_str());
    for (const auto& e : summary.elements) {
      std::printf("  element   %-12s %lld", e.name.c_str(), static_cast<long long>(e.count));
      if (!e.properties.empty()) {
        std::printf("  (");
        for (std::size_t i = 0; i < e.properties.size(); ++i)
          std::printf("%s%s", i ? ", " : "", e.properties[i].c_str());
        std::printf(")");
      }
      std::printf("\n");
    }
    std::printf("  points    %lld\n  faces     %lld\n", static_cast<long long>(mesh.num_vertices()),
                static_cast<long long>(mesh.num_faces()));
    std::printf("  normals   %s\n  colours   %s\n", mesh.vertices.has_normals() ? "yes" : "no",
                mesh.vertices.has_colors() ? "yes" : "no");
    if (!b.empty()) {
      std::printf("  bounds    [%.6g %.6g %.6g] .. [%.6g %.6g %.6g]\n  extent    %.6g x %.6g x %.6g\n",
                  b.min.x(), b.min.y(), b.min.z(), b.max.x(), b.max.y(), b.max.z(), b.extent().x(),
                  b.extent().y(), b.extent().z());
    }
    std::printf("  units     %s\n",
                unit ? (ToString(*unit) +
                        (*unit == LengthUnit::kMillimetre
                             ? " (likely)"
                             : " (likely; pass --input-units " + ToString(*unit) + " to other commands)"))
                           .c_str()
                     : "unknown");
  }

 private:
  std::string file_;
};

PECTUS_REGISTER_COMMAND(InfoCommand, 10);

}  // namespace

}  // namespace pectus::cli
