// pectus merge: align the overlapping sweeps of a scan (one joint adjustment of all poses, each held to
// the tracker's pose with its accuracy) and merge them into one cloud.
#include <omp.h>

#include <algorithm>
#include <cstdio>

#include "apps/command.h"
#include "shape/core/error.h"
#include "shape/core/log.h"
#include "shape/io/mesh_io.h"
#include "shape/io/stanford_conf.h"
#include "shape/surface/merge_sweeps.h"

namespace pectus::cli {
namespace {
namespace fs = std::filesystem;

class MergeCommand : public Command {
 public:
  std::string Name() const override { return "merge"; }
  std::string Summary() const override {
    return "Align overlapping sweeps (ICP + global adjustment) and merge them into one cloud";
  }
  std::string Example() const override {
    return "  cd ../shared/datasets/stanford_bunny\n"
           "  pectus merge bun*.ply chin.ply ear_back.ply top*.ply --poses start.conf --poses-out "
           "aligned.conf \\\n"
           "      --input-units m -o merged.ply --report r.json\n"
           "  pectus merge --poses bun.conf --input-units m -o merged.ply   (every sweep the .conf lists)\n"
           "  pectus merge sweep_*.ply -o merged.ply --smoothing 1.0 --spacing 0.8   (scanner poses = "
           "identity)";
  }
  void Configure(CLI::App* app) override {
    app->add_option("sweeps", sweeps_,
                    "Sweep files (PLY, OBJ, STL, PCD, XYZ); default: every sweep in --poses");
    app->add_option("-o,--output", output_, "Merged cloud (.ply keeps normals and the sweep index)")
        ->required();
    app->add_option("--poses", poses_in_,
                    "Starting poses, Stanford .conf (bmesh FILE tx ty tz qx qy qz qw); default identity");
    app->add_option("--poses-out", poses_out_, "Write the refined poses as a Stanford .conf (input units)");
    app->add_option("--input-units", units_,
                    "Unit of the sweeps and of the .conf translations: mm, cm, m, in")
        ->default_val("mm");
    app->add_flag("--no-refine", no_refine_, "Keep the given poses; only merge, filter and decimate");
    app->add_option("--anchor", anchor_, "Sweep whose pose is kept (file name); default the first");
    app->add_option("--smoothing", options_.smoothing_mm,
                    "Blending radius of overlapping sweeps (mm); 0 = none")
        ->default_val(0.0)
        ->check(CLI::NonNegativeNumber);
    app->add_option("--spacing", options_.target_spacing_mm,
                    "Decimate to this point spacing (mm); 0 = keep all")
        ->default_val(0.0)
        ->check(CLI::NonNegativeNumber);
    app->add_option("--outlier-ratio", options_.outlier_std_ratio,
                    "Statistical outlier removal: mean kNN distance above mean + RATIO std")
        ->default_val(3.0);
    app->add_option("--outlier-neighbours", options_.outlier_neighbours, "k of the outlier test; 0 = off")
        ->default_val(16);
    app->add_option("--tracker-deg", options_.tracker_deg,
                    "Tracker's rotation accuracy, 1 sd (deg): each starting pose is trusted this far; "
                    "0 with --tracker-mm 0: no prior, pairwise ICP first")
        ->capture_default_str()
        ->check(CLI::Range(0.0, 30.0));
    app->add_option("--tracker-mm", options_.tracker_mm, "Tracker's translation accuracy, 1 sd (mm)")
        ->capture_default_str()
        ->check(CLI::Range(0.0, 100.0));
    app->add_option("--tracker-lever", options_.tracker_lever_mm,
                    "Distance from the tracker's origin to the skin (mm): its rotation error moves the "
                    "sweep by deg x lever there")
        ->capture_default_str()
        ->check(CLI::Range(0.0, 1e4));
    app->add_option("--overlap-distance", options_.overlap_distance_mm,
                    "Starting search radius of overlaps (mm); 0 = 3 sd of two sweeps' relative tracker "
                    "error at the skin")
        ->capture_default_str()
        ->check(CLI::NonNegativeNumber);
    app->add_option("--min-overlap", options_.min_overlap_fraction,
                    "Link two sweeps sharing at least this fraction of the smaller one's area")
        ->capture_default_str()
        ->check(CLI::Range(0.0, 0.99));
    app->add_option("--max-rms", options_.pairwise.max_rms_mm,
                    "A pairwise fit worse than this RMS (mm) is not trusted")
        ->default_val(1.0);
  }
  std::vector<fs::path> Inputs() const override {
    std::vector<fs::path> in(sweeps_.begin(), sweeps_.end());
    if (!poses_in_.empty()) {
      in.push_back(poses_in_);
      if (sweeps_.empty()) {
        for (const auto& p : ReadStanfordConf(poses_in_))
          in.push_back(fs::path(poses_in_).parent_path() / p.file);
      }
    }
    return in;
  }

  void Run(Context* context) override {
    const auto staged = StageOutput(context, *this, output_);
    fs::path staged_poses;
    if (!poses_out_.empty()) staged_poses = StageOutput(context, *this, poses_out_);
    const LengthUnit unit = ParseLengthUnit(units_);
    const double mm_per_unit = MillimetresPer(unit);
    options_.refine_poses = !no_refine_;

    // Which files, with which starting poses.
    std::vector<std::string> files = sweeps_;
    std::vector<Rigid3> start;
    std::vector<std::string> conf_names;
    if (!poses_in_.empty()) {
      std::vector<ScanPose> poses = ReadStanfordConf(poses_in_);
      ScaleTranslations(mm_per_unit, &poses);
      if (files.empty()) {
        for (const auto& p : poses) files.push_back((fs::path(poses_in_).parent_path() / p.file).string());
      }
      for (const auto& f : files) {
        const auto name = fs::path(f).filename();
        auto it = std::find_if(poses.begin(), poses.end(),
                               [&](const ScanPose& p) { return fs::path(p.file).filename() == name; });
        if (it == poses.end()) ThrowBadInput(poses_in_, "has no pose for sweep '" + name.string() + "'");
        start.push_back(it->T_common_scan);
        conf_names.push_back(it->file);
      }
    } else {
      if (files.empty()) ThrowUsage("give sweep files, or --poses FILE.conf to take every sweep it lists");
      start.assign(files.size(), Rigid3::Identity());
      for (const auto& f : files) conf_names.push_back(fs::path(f).filename().string());
    }
    if (!anchor_.empty()) {
      auto it = std::find_if(files.begin(), files.end(), [&](const std::string& f) {
        return fs::path(f).filename() == fs::path(anchor_).filename();
      });
      if (it == files.end()) ThrowUsage("--anchor " + anchor_ + " is not one of the sweeps");
      options_.anchor = static_cast<std::size_t>(it - files.begin());
    }

    std::vector<PointCloud> clouds(files.size());
    {
      auto t = context->report.Stage("read");
      Progress progress("reading sweeps", static_cast<std::int64_t>(files.size()));
      ReadOptions ro;
      ro.input_units = unit;
      std::exception_ptr failure;
#pragma omp parallel for schedule(dynamic)
      for (std::size_t i = 0; i < files.size(); ++i) {
        try {
          clouds[i] = ReadPointCloud(files[i], ro);
        } catch (...) {
#pragma omp critical
          failure = std::current_exception();
        }
        progress.Advance();
      }
      if (failure) std::rethrow_exception(failure);
    }

    SweepMergeResult result;
    {
      auto t = context->report.Stage("merge");
      std::vector<std::string> names;
      for (const auto& f : files) names.push_back(fs::path(f).filename().string());
      result = MergeSweeps(clouds, start, options_, names);
    }
    context->report.AddTimes(result.timings_s);
    {
      auto t = context->report.Stage("write");
      WritePointCloud(staged, result.merged);
      if (!staged_poses.empty()) {
        std::vector<ScanPose> out;
        for (std::size_t i = 0; i < files.size(); ++i)
          out.push_back({conf_names[i], result.T_world_sweep[i]});
        ScaleTranslations(1.0 / mm_per_unit, &out);
        WriteStanfordConf(staged_poses, out);
      }
    }

    nlohmann::json sweeps = nlohmann::json::array();
    for (std::size_t i = 0; i < files.size(); ++i) {
      sweeps.push_back({{"file", files[i]},
                        {"points", clouds[i].size()},
                        {"correction_deg", result.correction_deg[i]},
                        {"correction_mm", result.correction_mm[i]}});
    }
    nlohmann::json pairs = nlohmann::json::array();
    for (const auto& p : result.pairs) {
      pairs.push_back({{"sweeps", {p.i, p.j}},
                       {"overlap_fraction", p.overlap_fraction},
                       {"rms_before_mm", p.rms_before_mm},
                       {"rms_after_mm", p.rms_after_mm},
                       {"median_distance_after_mm", p.median_after_mm},
                       {"pairwise_icp_success", p.pairwise_success},
                       {"pinned_directions", p.pinned_directions}});
    }
    auto& r = context->report.json();
    r["sweeps"] = sweeps;
    r["pairs"] = pairs;
    r["points_in"] = result.points_in;
    r["outliers_removed"] = result.outliers_removed;
    r["points_out"] = result.points_out;
    r["points"] = result.points_out;
    r["smoothing_mm"] = options_.smoothing_mm;
    r["spacing_mm"] = options_.target_spacing_mm;
    r["output"] = output_;
    r["message"] = result.message;
    Info(result.BriefReport());
  }

 private:
  std::vector<std::string> sweeps_;
  std::string output_, poses_in_, poses_out_, units_, anchor_;
  bool no_refine_ = false;
  SweepMergeOptions options_;
};

PECTUS_REGISTER_COMMAND(MergeCommand, 60);

}  // namespace
}  // namespace pectus::cli
