// pectus register: bring scans into one frame. A pair (moving to fixed), or a whole cohort (every scan to
// a reference, or groupwise by generalised Procrustes): landmarks for the coarse step, ICP for the fine.
#include <algorithm>
#include <filesystem>
#include <future>
#include <memory>
#include <optional>

#include "apps/command.h"
#include "apps/commands/register_io.h"
#include "registration/align_cohort.h"
#include "registration/register_pair.h"
#include "shape/core/error.h"
#include "shape/core/log.h"
#include "shape/core/number_format.h"
#include "shape/core/task_runner.h"
#include "shape/io/landmark_io.h"
#include "shape/io/mesh_io.h"
#include "shape/io/transform_io.h"

namespace pectus::cli {
namespace {
namespace fs = std::filesystem;

class RegisterCommand : public Command {
 public:
  std::string Name() const override { return "register"; }
  std::string Summary() const override {
    return "Align scans: landmarks then ICP, for a pair or a whole cohort (to a reference or groupwise)";
  }
  std::string Example() const override {
    return "  pectus register moving.ply --to fixed.ply --moving-landmarks a.mrk.json --fixed-landmarks "
           "b.mrk.json \\\n"
           "      -o moved.ply --transform T.json --report r.json\n"
           "  pectus register ../shared/datasets/stanford_bunny/bun045.ply --to "
           "../shared/datasets/stanford_bunny/bun000.ply \\\n"
           "      --input-units m --initial start.json --transform T.json\n"
           "  pectus register --cohort scans/ --groupwise -o aligned/ --write-moved\n"
           "  mpirun -n 8 pectus register --cohort scans/ -o aligned/   (the scans' fits shared over 8 "
           "ranks)\n"
           "  (cohort: every .ply/.obj/.stl/.pcd/.xyz in the folder; landmarks beside each scan as "
           "STEM.mrk.json,\n"
           "   STEM.fcsv or STEM.csv; writes STEM.T.json per scan and summary.json)\n"
           "  A poor fit is an error (exit 1) with the reason; nothing is written.";
  }
  void Configure(CLI::App* app) override {
    app->add_option("moving", moving_, "Scan to move (pair mode)");
    app->add_option("--to", fixed_, "Scan to align to (pair mode)");
    app->add_option("--moving-landmarks", moving_landmarks_,
                    "Landmarks on the moving scan (.mrk.json, .fcsv, .csv)");
    app->add_option("--fixed-landmarks", fixed_landmarks_, "The same labels on the fixed scan");
    app->add_option("--initial", initial_,
                    "JSON with \"T_target_source\": the start pose when there are no landmarks");
    app->add_option("-o,--output", output_,
                    "Pair: the moved scan. Cohort: the folder for transforms and summary");
    app->add_option("--transform", transform_, "Pair: write T_target_source (4x4, row-major, mm) as JSON");
    app->add_option("--cohort", cohort_, "Folder of scans to bring into one frame (cohort mode)");
    app->add_option("--reference", reference_, "Cohort: the reference scan's file name (default: the first)");
    app->add_flag("--groupwise", groupwise_, "Cohort: generalised Procrustes to the evolving mean");
    app->add_flag("--write-moved", write_moved_, "Cohort: also write every scan moved into the cohort frame");
    app->add_flag(
        "--keep-going", keep_going_,
        "Cohort: a scan that fails is left out (listed in summary.json) instead of failing the run");
    app->add_flag("--scale", scale_, "Estimate a similarity (scale) from the landmarks");
    app->add_option("--input-units", units_, "Unit of the scans' and landmarks' coordinates: mm, cm, m, in")
        ->default_val("mm");
    app->add_option("--method", method_, "ICP error: point-to-plane or symmetric")
        ->default_val("point-to-plane");
    app->add_option("--loss", loss_, "Robust loss: none, huber, cauchy, tukey")->default_val("cauchy");
    app->add_option("--trim", trim_, "Drop this fraction of the worst pairs each iteration (default 0)");
    app->add_option("--max-distance", max_distance_,
                    "Correspondence gate of the first (coarsest) level, mm (default 20)");
    app->add_option("--final-distance", final_distance_,
                    "Gate of the last level, mm (default: 3 point spacings for a pair, 10 mm for a cohort of "
                    "different people)");
    app->add_option(
        "--patch-radius", patch_radius_,
        "ICP only on surface patches of this radius (mm) around the moving landmarks (default: all)");
    app->add_option(
        "--max-rms", max_rms_,
        "A fit with a larger RMS distance (mm) is a failure (default 1 for a pair, 5 for a cohort)");
    app->add_option(
        "--min-inliers", min_inliers_,
        "A fit with a smaller fraction of the moving scan within the last gate of the fixed one is a "
        "failure (default 0.3)");
    app->add_option("--pose-sd-fraction", pose_sd_fraction_,
                    "ICP's last sample grows until sampling adds at most this fraction of the residuals' "
                    "robust scale to the pose's standard error; 0 keeps 30000 points (default 0.01)");
    app->add_option(
           "--plane-points", plane_points_,
           "ICP's plane at a moving point passes through the mean of this many nearest fixed points, "
           "1 to 4; 1 = the nearest point's own plane (default 4)")
        ->check(CLI::Range(1, kMaxPlanePoints));
    app->add_flag("--no-refine", no_refine_, "Landmarks (or --initial) only, no ICP");
    app->add_option("--work", work_,
                    "Cohort: folder of the scans' fits until the outputs are written, on a file system every "
                    "rank sees (default: OUTDIR/.pectus-work; emptied after a complete run)");
    app->add_flag("--resume", resume_, "Cohort: keep the fits of a killed run and compute only the rest");
    app->add_option(
        "--shard", shard_,
        "Cohort, to the reference: K/N: only share K of N of the scans (a job array without MPI), "
        "kept in the work folder for --gather");
    app->add_flag("--gather", gather_,
                  "Cohort: write the outputs from the fits every share made (after --shard)");
  }
  std::vector<fs::path> Inputs() const override {
    std::vector<fs::path> in;
    for (const std::string& s : {moving_, fixed_, moving_landmarks_, fixed_landmarks_, initial_}) {
      if (!s.empty()) in.push_back(s);
    }
    for (const auto& s : cohort_files_) in.push_back(s);
    return in;
  }

  void Run(Context* context) override {
    // Defaults: a pair is two scans of one surface; a cohort holds different people (CohortOptions).
    options_ = cohort_.empty() ? PairRegistrationOptions() : CohortOptions().pair;
    if (trim_) options_.icp.trim_fraction = *trim_;
    if (max_distance_) options_.icp.initial_max_distance_mm = *max_distance_;
    if (final_distance_) options_.icp.final_max_distance_mm = *final_distance_;
    if (patch_radius_) options_.patch_radius_mm = *patch_radius_;
    if (max_rms_) options_.icp.max_rms_mm = *max_rms_;
    if (min_inliers_) options_.icp.min_inlier_fraction = *min_inliers_;
    if (pose_sd_fraction_) options_.icp.target_pose_sd_fraction = *pose_sd_fraction_;
    if (plane_points_) options_.icp.plane_points = *plane_points_;
    options_.landmarks.estimate_scale = scale_;
    options_.refine = !no_refine_;
    options_.icp.method = ParseIcpMethod(method_);
    options_.icp.loss = ParseRobustLoss(loss_);
    read_options_.input_units = ParseLengthUnit(units_);
    landmark_options_.input_units = read_options_.input_units;
    std::string why;
    if (!options_.IsValid(&why)) ThrowUsage(why);
    if (!cohort_.empty()) {
      if (!moving_.empty() || !fixed_.empty())
        ThrowUsage("give either a pair (MOVING --to FIXED) or --cohort DIR");
      RunCohort(context);
    } else {
      if (moving_.empty() || fixed_.empty()) ThrowUsage("give MOVING --to FIXED, or --cohort DIR");
      if (groupwise_ || write_moved_ || keep_going_ || !reference_.empty() || !work_.empty() || resume_ ||
          !shard_.empty() || gather_) {
        ThrowUsage(
            "--groupwise, --reference, --write-moved, --keep-going, --work and --resume are for --cohort");
      }
      RunPair(context);
    }
  }

 private:
  void RunPair(Context* context) {
    if (moving_landmarks_.empty() != fixed_landmarks_.empty()) {
      ThrowUsage("give landmarks for both scans (--moving-landmarks and --fixed-landmarks) or for neither");
    }
    if (!initial_.empty() && !moving_landmarks_.empty())
      ThrowUsage("--initial is for registration without landmarks");
    fs::path staged_output, staged_transform;
    if (!output_.empty()) {
      FormatFromPath(output_);  // an unknown output type is a usage error before any work
      staged_output = StageOutput(context, *this, output_);
    }
    if (!transform_.empty()) staged_transform = StageOutput(context, *this, transform_);
    Report& report = context->report;

    PointCloud moving, fixed;
    std::optional<LandmarkSet> moving_lm, fixed_lm;
    Similarity3 initial;
    std::unique_ptr<IcpTarget> target;
    Eigen::Index fixed_points = 0;
    {
      auto t = report.Stage("read");
      // The fixed scan is read and prepared as ICP's target (centred, its k-d tree built) on a second
      // thread while this one reads the moving scan and the landmarks; with --threads 1, here, in turn.
      const PairRegistrationOptions prepare = options_;  // this thread sets the landmark names meanwhile
      auto prepared = std::async(context->threads > 1 ? std::launch::async : std::launch::deferred, [&] {
        fixed = ReadPointCloud(fixed_, read_options_);
        fixed_points = fixed.size();
        // ICP's target takes over the scan's arrays; the scan itself is needed only without ICP.
        return prepare.refine ? PrepareTarget(std::move(fixed), prepare, fixed_) : nullptr;
      });
      // Meanwhile this thread starts its OpenMP workers, which ICP's finer levels use: here the fixed
      // scan's read hides the time they take to start (docs/registration.md, "The workers started early").
      if (context->threads > 1) StartWorkerThreads();
      moving = ReadPointCloud(moving_, read_options_);
      if (!moving_landmarks_.empty()) {
        moving_lm = ReadLandmarks(moving_landmarks_, landmark_options_);
        fixed_lm = ReadLandmarks(fixed_landmarks_, landmark_options_);
        options_.moving_landmarks_name = moving_landmarks_;
        options_.fixed_landmarks_name = fixed_landmarks_;
      }
      if (!initial_.empty()) initial = ReadTransformJson(initial_);
      target = prepared.get();
    }
    // A rigid pose written with doubles reads back with a scale of 1 to rounding (cbrt of a determinant).
    if (!(std::abs(initial.scale - 1.0) <= 1e-9)) {
      ThrowBadInput(initial_,
                    "the initial pose must be rigid (scale 1), not " + FormatSignificant(initial.scale, 12));
    }
    initial.scale = 1.0;
    PairRegistrationResult r;
    {
      auto t = report.Stage("register");
      r = target ? RegisterPair(*target, moving, fixed_lm ? &*fixed_lm : nullptr,
                                moving_lm ? &*moving_lm : nullptr, initial, options_)
                 : RegisterPair(fixed, moving, fixed_lm ? &*fixed_lm : nullptr,
                                moving_lm ? &*moving_lm : nullptr, initial, options_);
    }
    report["moving"] = moving_;
    report["fixed"] = fixed_;
    report["moving_points"] = moving.size();
    report["fixed_points"] = fixed_points;
    if (r.landmarks) {
      report["landmarks"] = LandmarkJson(*r.landmarks);
      report["landmark_rms_after_mm"] = r.landmark_rms_mm;
      for (const std::string& label : r.landmarks->unmatched) {
        Warn("landmark '" + label + "' is on one scan only and was not used");
      }
    }
    if (r.icp) report["icp"] = IcpJson(*r.icp);
    report.AddTimes(r.timings_s);
    report["transform"] = TransformToJson(r.T_target_source);
    report["success"] = r.success;
    report["message"] = r.message;
    if (!r.success) {
      ThrowFailure("registration of " + moving_ + " to " + fixed_ + " failed: " + r.message +
                   " (nothing written; see --max-rms, --min-inliers, --max-distance, --final-distance)");
    }
    Info("registered " + moving_ + " to " + fixed_ + ": " + r.BriefReport());

    auto t = report.Stage("write");
    if (!transform_.empty()) {
      WriteTransformJson(staged_transform, r.T_target_source, PairTransformExtra(moving_, fixed_, r));
    }
    if (!output_.empty()) {
      TriangleMesh mesh = ReadMesh(moving_, read_options_);  // keeps faces if the moving scan is a mesh
      TransformInPlace(r.T_target_source, &mesh);
      WriteMesh(staged_output, mesh);
    }
  }

  void RunCohort(Context* context) {
    if (output_.empty()) ThrowUsage("--cohort needs -o OUTDIR for the transforms and summary.json");
    if (!transform_.empty() || !initial_.empty() || !moving_landmarks_.empty() || !fixed_landmarks_.empty()) {
      ThrowUsage(
          "--transform, --initial and --*-landmarks are for pair mode; a cohort's landmarks lie beside its "
          "scans");
    }
    if (!fs::is_directory(cohort_)) ThrowBadInput(cohort_, "is not a folder");
    const std::vector<fs::path> files = CohortScanFiles(cohort_);
    if (files.size() < 2)
      ThrowBadInput(cohort_, "holds " + std::to_string(files.size()) + " scans; a cohort needs two or more");
    cohort_files_ = files;

    CohortOptions co;
    co.pair = options_;
    co.mode = groupwise_ ? CohortMode::kGroupwise : CohortMode::kToReference;
    if (!reference_.empty()) {
      const auto it = std::find_if(files.begin(), files.end(), [&](const fs::path& p) {
        return p.filename() == fs::path(reference_).filename();
      });
      if (it == files.end()) ThrowUsage("reference '" + reference_ + "' is not a scan in " + cohort_);
      co.reference = static_cast<int>(it - files.begin());
    }

    // Stage every output first (the leader, which writes them): a refused overwrite fails before any work.
    const fs::path out = output_;
    const TaskShare share = shard_.empty() ? TaskShare{} : ParseTaskShare(shard_);
    if (!share.whole() && (gather_ || context->runner->Processes() > 1))
      ThrowUsage("--shard runs one share on its own: not with --gather, nor under mpirun");
    if ((!share.whole() || gather_) && groupwise_)
      ThrowUsage(
          "--shard and --gather are for the registration to a reference: the groupwise rounds need "
          "every scan's fit of the round before (run --groupwise under mpirun or on one machine)");
    SerialTaskRunner share_runner(share);
    const bool leader = context->runner->IsLeader() && share.whole();
    std::vector<fs::path> staged_T(files.size()), staged_moved(files.size());
    fs::path staged_summary;
    if (leader) {
      for (std::size_t i = 0; i < files.size(); ++i) {
        staged_T[i] = StageOutput(context, *this, out / (files[i].stem().string() + ".T.json"));
        if (write_moved_)
          staged_moved[i] = StageOutput(context, *this, out / (files[i].stem().string() + ".ply"));
      }
      staged_summary = StageOutput(context, *this, out / "summary.json");
    }

    std::vector<CohortScan> scans;
    {
      auto t = context->report.Stage("read");
      scans = ReadCohortScans(files, read_options_, landmark_options_);
    }
    // The scans' fits on the task farm (docs/cluster.md): this process's threads, or the MPI ranks.
    CohortFarm farm;
    farm.runner = share.whole() ? context->runner : &share_runner;
    farm.work = work_.empty() ? out / ".pectus-work" : fs::path(work_);
    farm.resume = resume_;
    farm.fits_only = !share.whole();
    farm.gather = gather_;
    CohortResult r;
    {
      auto t = context->report.Stage("register");
      r = AlignCohort(scans, co, farm);
    }
    if (!share.whole()) {
      Info("register: share " + shard_ + " done; its scans' fits are in " + farm.work.string() +
           " (then: the same command with --gather)");
    }
    if (!leader) return;

    std::vector<std::string> failed;
    const nlohmann::json summary = CohortSummary(files, scans, r, co, &failed);
    context->report["cohort"] = summary;
    if (!failed.empty()) {
      std::string text;
      for (const auto& f : failed) text += "\n  " + f;
      if (!keep_going_) {
        ThrowFailure(
            std::to_string(failed.size()) + " of " + std::to_string(files.size()) +
            " scans could not be registered (nothing written; --keep-going writes the others):" + text);
      }
      Warn(std::to_string(failed.size()) + " scans left out:" + text);
    }

    auto t = context->report.Stage("write");
    for (std::size_t i = 0; i < files.size(); ++i) {
      if (!r.success[i]) continue;
      WriteTransformJson(
          staged_T[i], r.T_frame_scan[i],
          {{"source", files[i].string()},
           {"target", "cohort frame (reference " + summary["reference"].get<std::string>() + ")"},
           {"rms_mm", r.rms_mm[i]},
           {"inlier_fraction", r.inlier_fraction[i]}});
      if (write_moved_) {
        TriangleMesh mesh = ReadMesh(files[i], read_options_);
        TransformInPlace(r.T_frame_scan[i], &mesh);
        WriteMesh(staged_moved[i], mesh);
      }
    }
    WriteFileAtomically(staged_summary, summary.dump(2) + "\n");
    RemoveCohortFits(farm.work);  // every output is staged
    Info(r.BriefReport() + " into the frame of " + summary["reference"].get<std::string>() + " -> " +
         output_);
  }

  std::string moving_, fixed_, moving_landmarks_, fixed_landmarks_, initial_, output_, transform_, cohort_,
      reference_, work_, shard_;
  std::string units_, method_, loss_;
  bool groupwise_ = false, write_moved_ = false, keep_going_ = false, scale_ = false, no_refine_ = false,
       resume_ = false, gather_ = false;
  std::optional<double> trim_, max_distance_, final_distance_, patch_radius_, max_rms_, min_inliers_,
      pose_sd_fraction_;
  std::optional<int> plane_points_;
  PairRegistrationOptions options_;
  ReadOptions read_options_;
  LandmarkReadOptions landmark_options_;
  std::vector<fs::path> cohort_files_;
};

PECTUS_REGISTER_COMMAND(RegisterCommand, 50);

}  // namespace
}  // namespace pectus::cli
