// pectus pipeline COHORT_DIR --out OUT_DIR: the main job. From a folder of raw subjects (sweeps +
// landmarks, as `pectus synth cohort` writes them) to the average chest with its modes, model quality,
// each subject's distance to the mean, and one HTML report (pictures and numbers).
#include "apps/command.h"
#include "apps/task_farm_options.h"
#include "shape/core/atomic_file.h"
#include "shape/core/error.h"
#include "shape/core/log.h"
#include "shape/model/profile_fit.h"
#include "shape/model/shape_grid.h"
#include "shape/pipeline/cohort_pipeline.h"
#include "shape/pipeline/pipeline_report.h"
#include "shape/pipeline/write_pipeline_outputs.h"

namespace pectus::cli {
namespace {

namespace fs = std::filesystem;

class PipelineCommand : public Command {
 public:
  std::string Name() const override { return "pipeline"; }
  std::string Summary() const override {
    return "The main job: raw sweeps of a cohort to the average chest, its modes, quality and an HTML report";
  }
  std::string Example() const override {
    return "  pectus synth cohort --subjects 11 --seed 7 --out cohort\n"
           "  pectus pipeline cohort --out results --report results/pipeline.json\n"
           "  (then open results/report.html; per subject: merge -> reconstruct -> register to the "
           "reference\n"
           "   by landmarks then ICP -> resample on the landmark grid; then the model and distance maps.\n"
           "   A subject that fails is listed in the report and the others go on.)\n"
           "  mpirun -n 64 pectus pipeline cohort --out results      (subjects shared out over 64 ranks)\n"
           "  pectus pipeline cohort --out results --resume          (after a killed run: only what is "
           "missing)\n"
           "  pectus pipeline cohort --out results --shard 2/8       (share 2 of 8 of a job array; then:)\n"
           "  pectus pipeline cohort --out results --gather          (the shares' subjects to the model)\n"
           "  (Each subject's results are committed to the work folder as they finish; the outputs are the\n"
           "   same bytes for any number of ranks or shares. docs/cluster.md)";
  }
  void Configure(CLI::App* app) override {
    app->add_option("cohort", cohort_,
                    "Folder with one sub-folder per subject (sweep_NN.ply + landmarks.mrk.json)")
        ->required();
    app->add_option("-o,--out", out_, "Output folder (report.html, model.h5, figures/, subjects/)")
        ->required();
    app->add_option("--sweeps", sweep_pattern_, "Sweep file names in a subject folder")
        ->default_val("sweep_*.ply");
    app->add_option("--landmarks-name", landmarks_name_, "Landmarks file name in a subject folder")
        ->default_val("landmarks.mrk.json");
    app->add_option("--reference", options_.reference,
                    "Reference subject (default: the first that reconstructs)");
    app->add_option("--grid", grid_, "Resampling grid LATERALxSTERNAL")->default_val("51x101");
    app->add_option("--fit", fit_, "Profile curve: spline or polynomial")->default_val("spline");
    app->add_option("--crop-margin", options_.crop_margin_mm,
                    "Sweeps cut to the landmark ROI widened by this, mm (0: whole sweeps)")
        ->default_val(options_.crop_margin_mm);
    app->add_option("--surface-spacing", options_.reconstruct.spacing_mm,
                    "Isosurface step of the surfaces, mm")
        ->default_val(options_.reconstruct.spacing_mm);
    app->add_option("--merge-spacing", options_.merge.target_spacing_mm,
                    "Merged cloud decimated to this spacing, mm")
        ->default_val(options_.merge.target_spacing_mm);
    app->add_option("--samples", options_.quality_options.specificity_samples,
                    "Random shapes for specificity")
        ->default_val(options_.quality_options.specificity_samples);
    app->add_option("--impute-gap", options_.impute_gap_mm,
                    "Grid vertices farther than this from the scan data (mm) are filled from the other "
                    "subjects before the model; 0: off")
        ->default_val(options_.impute_gap_mm);
    app->add_option("--impute-scale", options_.imputation.local_scale_mm,
                    "Length (mm) over which a filled region is joined to the seen vertices about it; 0: "
                    "the others' prediction alone")
        ->default_val(options_.imputation.local_scale_mm);
    app->add_option("--impute-others", options_.imputation.max_others,
                    "The model a subject is filled from: at most this many other subjects (the cohort's "
                    "first; only their fills are iterated, each subject beyond them is filled once)")
        ->check(CLI::Range(2, 1 << 20))
        ->default_val(options_.imputation.max_others);
    app->add_flag("--no-quality", no_quality_, "Skip compactness, generalization and specificity");
    app->add_option("--distance-range", report_.distance_range_mm,
                    "Colour scale of the distance maps, +-mm (0: auto)")
        ->default_val(0.0);
    app->add_flag("--no-surfaces", no_surfaces_, "Do not write each subject's registered surface");
    farm_.Configure(app, "subjects", "OUT/.pectus-work");
  }
  std::vector<fs::path> Inputs() const override {
    std::vector<fs::path> in;
    for (const CohortSubject& s : subjects_) {
      in.insert(in.end(), s.sweeps.begin(), s.sweeps.end());
      in.push_back(s.landmarks);
    }
    return in;
  }

  void Run(Context* context) override {
    options_.resample.grid = ParseGridSize(grid_);
    options_.resample.fit.kind = ParseProfileFitKind(fit_);
    options_.quality = !no_quality_;
    options_.keep_surfaces = !no_surfaces_;
    std::string why;
    if (!options_.IsValid(&why)) ThrowUsage(why);
    const fs::path out(out_);
    subjects_ = FindCohortSubjects(cohort_, sweep_pattern_, landmarks_name_);
    PipelineRun run;
    run.runner = farm_.Runner(context->runner);
    run.work = farm_.Work(out / ".pectus-work");
    run.resume = farm_.resume();
    run.subjects_only = farm_.share_only();
    run.gather = farm_.gather();
    // 8-9. Each subject's files on the farm too (after the model): its meshes, then its distance picture
    // on the cohort's colour scale; the leader moves them into the outputs.
    run.subject_files = [](const SubjectOutcome& s, const fs::path& folder) {
      WriteSubjectFiles(s, [&](const fs::path& name) {
        fs::create_directories((folder / name).parent_path());
        return folder / name;
      });
    };
    run.picture_scale = [this](const std::vector<SubjectOutcome>& subjects) {
      return DistanceMapRange(subjects, report_);
    };
    run.subject_pictures = [this](const SubjectOutcome& s, double scale, const fs::path& folder) {
      if (s.to_mean.distances.size() == 0) return;
      const ReportFile picture = SubjectDistancePicture(s, scale, report_);
      fs::create_directories((folder / picture.path).parent_path());
      WriteFileAtomically(folder / picture.path, picture.bytes);
    };
    // 10. The files of the model alone (model.h5, its tables, the report's figures of it) on the farm too,
    // one task each; the leader moves them into the outputs as well.
    run.model_files = [this](const PipelineResult& result) {
      return ModelOutputFiles(*result.model, ModelInfo(result.reference), report_);
    };
    const bool leader = farm_.Leader(*context->runner);
    fs::path html;
    if (leader) html = StageOutput(context, *this, out / "report.html");  // refuses an input early
    Info("pipeline: " + std::to_string(subjects_.size()) + " subjects in " + cohort_ + " (" +
         run.runner->Describe() + ")");

    // 1-8. Every stage, subject by subject (the library reports failures per subject). Once the leader has
    // written the outputs, every process removes its share of the subjects' results
    // (RemoveSubjectResultsOnFarm; it tells the others to keep them if anything failed, for --resume).
    std::vector<std::string> names;
    for (const CohortSubject& s : subjects_) names.push_back(s.name);
    bool removing = false;
    try {
      Pipeline(context, run, leader, html);
      if (farm_.share_only()) return;
      removing = true;
      const double seconds = RemoveSubjectResultsOnFarm(*run.runner, run.work, names, true);
      if (leader) {
        Timings removed;
        removed.Add("remove results", seconds);
        context->report.AddTimes(removed);
      }
    } catch (...) {
      if (!farm_.share_only() && !removing) RemoveSubjectResultsOnFarm(*run.runner, run.work, names, false);
      throw;
    }
  }

 private:
  // The run and, on the leader, its outputs (staged).
  void Pipeline(Context* context, const PipelineRun& run, bool leader, const fs::path& html) {
    const fs::path out(out_);
    PipelineResult result;
    {
      auto t = context->report.Stage("pipeline");
      Progress progress("pipeline: subjects through surface and resampling",
                        2 * static_cast<std::int64_t>(subjects_.size()));
      result = RunCohortPipeline(
          subjects_, options_,
          [&](const SubjectOutcome& s, const std::string& stage) {
            if (!s.failed_stage.empty() &&
                (stage == "surface" || s.failed_stage == "register" || s.failed_stage == "resample")) {
              Warn(s.name + " failed at " + s.failed_stage + ": " + s.error);
            }
            progress.Advance();
          },
          run);
    }
    if (farm_.share_only()) {
      Info("pipeline: share " + farm_.shard_text() + " done; its subjects' results are in " +
           run.work.string() + " (then: the same command with --gather)");
    }
    if (!leader) return;
    context->report.AddTimes(result.timings_s);
    if (!result.imputation_message.empty()) Info("pipeline: " + result.imputation_message);

    // 9. Files: the model, tables, meshes per subject, and the report with its figures (the library writes
    // them; the app stages each one for the run's transaction).
    auto t = context->report.Stage("write");
    report_.run = {{"command", "pectus pipeline " + cohort_ + " --out " + out_},
                   {"subjects", subjects_.size()},
                   {"grid", grid_},
                   {"profile fit", fit_},
                   {"threads", context->threads}};
    // The model's own files and its figures were made on the farm (run.model_files): the quality curves'
    // table, each subject's files and those moved in at the commit, the report.
    const fs::path html_target = out / "report.html";
    auto stage = [&](const fs::path& target) {
      return target == html_target ? html : StageOutput(context, *this, target);
    };
    auto move = [&](const fs::path& from, const fs::path& target) {
      MoveOutputAtCommit(context, *this, from, target);
    };
    WriteModelFiles(nullptr, result.quality ? &*result.quality : nullptr, ModelInfo(result.reference), out,
                    stage);
    WritePipelineOutputs(result, report_, ModelInfo(result.reference), out, stage, run.work,
                         /*model_files_written=*/true, move);
    // The outputs in place (the subjects' files moved from the work folder) before the work folder is
    // removed; the run's JSON report, written last, is committed after it.
    context->outputs.CommitAll();
    nlohmann::json summary = PipelineJson(result);
    for (const auto& [key, value] : summary.items()) context->report[key] = value;
    context->report["cohort"] = cohort_;
    context->report["out"] = out_;
    context->report["subjects_total"] = subjects_.size();
    context->report["grid"] = {{"lateral", options_.resample.grid.lateral},
                               {"sternal", options_.resample.grid.sternal}};
    context->report["profile_fit"] = ToString(options_.resample.fit.kind);
    Info("pipeline: " + result.BriefReport() + "; report: " + (out / "report.html").string());
  }

  // What model.h5 says of its source (its /pectus info).
  nlohmann::json ModelInfo(const std::string& reference) const {
    return {{"source", "pectus pipeline"}, {"cohort", cohort_}, {"reference", reference}};
  }

  std::string cohort_, out_, sweep_pattern_, landmarks_name_, grid_, fit_;
  TaskFarmOptions farm_;
  bool no_quality_ = false, no_surfaces_ = false;
  PipelineOptions options_;
  PipelineReportOptions report_;
  std::vector<CohortSubject> subjects_;
};

PECTUS_REGISTER_COMMAND(PipelineCommand, 110);

}  // namespace
}  // namespace pectus::cli
