// pectus place: put scanner sweeps into one frame with known poses (a Stanford .conf) and write them
// as one cloud, each point tagged with its sweep.
#include <omp.h>

#include <algorithm>
#include <cstdio>

#include "apps/command.h"
#include "shape/core/error.h"
#include "shape/core/log.h"
#include "shape/io/mesh_io.h"
#include "shape/io/stanford_conf.h"

namespace pectus::cli {
namespace {

class PlaceCommand : public Command {
 public:
  std::string Name() const override { return "place"; }
  std::string Summary() const override {
    return "Place sweeps by the poses of a .conf file and write one merged cloud";
  }
  std::string Example() const override {
    return "  pectus place --poses ../shared/datasets/stanford_bunny/bun.conf --input-units m \\\n"
           "      -o bunny_placed.ply --report placed.json\n"
           "  (reads every file the .conf lists, beside it; each point gets a 'sweep' scalar)";
  }
  void Configure(CLI::App* app) override {
    app->add_option("--poses", conf_, "Stanford .conf: bmesh FILE tx ty tz qx qy qz qw per sweep")
        ->required();
    app->add_option("sweeps", sweeps_, "Only these sweeps (file names as in the .conf); default all");
    app->add_option("-o,--output", output_, "Merged cloud to write (.ply keeps the sweep index)")->required();
    app->add_option("--input-units", units_,
                    "Unit of the sweeps and of the .conf translations: mm, cm, m, in")
        ->default_val("mm");
  }
  std::vector<std::filesystem::path> Inputs() const override {
    std::vector<std::filesystem::path> in{conf_};
    for (const auto& p : ReadStanfordConf(conf_))
      in.push_back(std::filesystem::path(conf_).parent_path() / p.file);
    return in;
  }

  void Run(Context* context) override {
    const auto staged = StageOutput(context, *this, output_);
    const LengthUnit unit = ParseLengthUnit(units_);
    std::vector<ScanPose> poses = ReadStanfordConf(conf_);
    ScaleTranslations(MillimetresPer(unit), &poses);
    if (!sweeps_.empty()) {
      std::vector<ScanPose> chosen;
      for (const auto& s : sweeps_) {
        auto it = std::find_if(poses.begin(), poses.end(), [&](const ScanPose& p) {
          return p.file == s ||
                 std::filesystem::path(p.file).filename() == std::filesystem::path(s).filename();
        });
        if (it == poses.end()) ThrowBadInput(conf_, "has no pose for sweep '" + s + "'");
        chosen.push_back(*it);
      }
      poses = chosen;
    }
    const auto folder = std::filesystem::path(conf_).parent_path();
    std::vector<PointCloud> clouds(poses.size());
    {
      auto t = context->report.Stage("read");
      Progress progress("reading sweeps", static_cast<std::int64_t>(poses.size()));
      ReadOptions options;
      options.input_units = unit;
      std::exception_ptr failure;
#pragma omp parallel for schedule(dynamic)
      for (std::size_t i = 0; i < poses.size(); ++i) {
        try {
          clouds[i] = ReadPointCloud(folder / poses[i].file, options);
        } catch (...) {
#pragma omp critical
          failure = std::current_exception();
        }
        progress.Advance();
      }
      if (failure) std::rethrow_exception(failure);
    }
    PointCloud merged;
    nlohmann::json sweeps = nlohmann::json::array();
    {
      auto t = context->report.Stage("place");
      for (std::size_t i = 0; i < poses.size(); ++i) {
        PointCloud& c = clouds[i];
        TransformInPlace(Similarity3::FromRigid(poses[i].T_common_scan), &c);
        c.scalars["sweep"] = Eigen::VectorXd::Constant(c.size(), static_cast<double>(i));
        sweeps.push_back({{"file", poses[i].file}, {"points", c.size()}});
        merged.Append(c);
      }
    }
    {
      auto t = context->report.Stage("write");
      WritePointCloud(staged, merged);
    }
    const Bounds3 b = ComputeBounds(merged.positions);
    context->report["sweeps"] = sweeps;
    context->report["points"] = merged.size();
    context->report["output"] = output_;
    context->report["bounds_mm"] = {{"min", {b.min.x(), b.min.y(), b.min.z()}},
                                    {"max", {b.max.x(), b.max.y(), b.max.z()}}};
    Info("placed " + std::to_string(poses.size()) + " sweeps, " + std::to_string(merged.size()) +
         " points -> " + output_);
  }

 private:
  std::string conf_, output_, units_;
  std::vector<std::string> sweeps_;
};

PECTUS_REGISTER_COMMAND(PlaceCommand, 30);

}  // namespace

}  // namespace pectus::cli
