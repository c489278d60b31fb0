// pectus synth cohort|subject|pair|patient: synthetic handheld chest scans with their ground truth
// (docs/datasets.md).
#include <fstream>
#include <optional>
#include <sstream>

#include "apps/command.h"
#include "datasets/chest_population.h"
#include "datasets/patient_table.h"
#include "datasets/scan_writer.h"
#include "datasets/synth.h"
#include "datasets/synth_preview.h"
#include "shape/core/atomic_file.h"
#include "shape/core/error.h"
#include "shape/core/log.h"

namespace pectus::cli {
namespace {

namespace ds = pectus::datasets;
namespace fs = std::filesystem;

// A subject's record in the work folder (its size and points), written by the task that made it.
nlohmann::json ReadRecord(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream text;
  text << in.rdbuf();
  nlohmann::json j = nlohmann::json::parse(text.str(), nullptr, false);
  if (!in || j.is_discarded() || !j.contains("bytes") || !j.contains("points"))
    ThrowBadInput(path.string(), "is not a subject's record of `pectus synth` (remove the work folder)");
  return j;
}

class SynthCommand : public Command {
 public:
  std::string Name() const override { return "synth"; }
  std::string Summary() const override {
    return "Synthetic handheld chest scans with ground truth: a cohort, a subject, a growth pair, a patient";
  }
  std::string Example() const override {
    return "  pectus synth cohort --subjects 11 --seed 7 --out cohort      # 11 normal chests, 5 sweeps "
           "each\n"
           "  pectus synth cohort --subjects 20 --pectus-fraction 0.5 --noise 0.3 --out mixed\n"
           "  pectus synth subject --seed 3 --pectus-depth 35 --pectus-type cup --torsion 15 --out pe\n"
           "  pectus synth pair --seed 3 --pectus-depth 25 --years 2 --out pair  # pair/pre, pair/post\n"
           "  pectus synth patient --row 57 --out p57 --table "
           "../shared/datasets/patients/nuss_ct_parameters.csv\n"
           "Each subject folder holds sweep_NN.ply (the scanner's points), landmarks.mrk.json and truth/\n"
           "(surface.ply, chest_wall.ply, poses.json, poses.conf, landmarks.mrk.json, subject.json,\n"
           "sweep_NN.ply); a cohort also gets population/ (exact mean and modes). Frame: mm, x to the\n"
           "subject's left, y up, z anterior.";
  }

  void Configure(CLI::App* app) override {
    app->require_subcommand(1, 1);
    cohort_ =
        app->add_subcommand("cohort", "Subjects drawn from the population, with its true mean and modes");
    cohort_->add_option("--subjects", cohort_options_.subjects, "Number of subjects")
        ->capture_default_str()
        ->check(CLI::Range(1, 10000));
    cohort_->add_option("--pectus-fraction", subject_.pectus.fraction, "Share of subjects given a depression")
        ->capture_default_str();
    cohort_->add_option("--pectus-min", subject_.pectus.depth_min_mm, "Shallowest drawn depression (mm)")
        ->capture_default_str();
    cohort_->add_option("--pectus-max", subject_.pectus.depth_max_mm, "Deepest drawn depression (mm)")
        ->capture_default_str();
    cohort_->add_option("--cup-fraction", subject_.pectus.cup_fraction, "Share of cup-type depressions")
        ->capture_default_str();
    cohort_->add_option("--modes", modes_, "True modes written to population/")->capture_default_str();
    cohort_->add_option("--grid", grid_, "Shape grid of the true statistics: NUxNV")->capture_default_str();
    subject_cmd_ = app->add_subcommand("subject", "One subject, optionally with a given depression");
    subject_cmd_->add_option("--index", index_, "Which subject of the seed's population draw")
        ->capture_default_str();
    pair_ = app->add_subcommand("pair", "One subject scanned twice: now (pre/) and after growth (post/)");
    pair_->add_option("--index", index_, "Which subject of the seed's population draw")
        ->capture_default_str();
    pair_->add_option("--years", growth_.years, "Years of growth between the scans")->capture_default_str();
    pair_->add_option("--depth-change", growth_.pectus_depth_factor, "Depression depth multiplied by this")
        ->capture_default_str();
    patient_ = app->add_subcommand("patient", "Chests of Nuss patients from their CT parameters");
    patient_->add_option("--row", rows_, "Patient number (repeatable)");
    patient_->add_flag("--all", all_rows_, "Every patient of the table");
    patient_->add_option("--table", table_, "The CT parameter table (CSV)")->capture_default_str();
    for (CLI::App* sub : {cohort_, subject_cmd_, pair_, patient_}) {
      sub->fallthrough();  // --report, --threads, --quiet belong to `synth`
      sub->footer("\nExample:\n" + Example());
      AddCommonOptions(sub);
      if (sub == subject_cmd_ || sub == pair_) AddPectusOptions(sub);
    }
  }

  std::vector<std::filesystem::path> Inputs() const override {
    if (patient_ && patient_->parsed()) return {table_};
    return {};
  }

  void Run(Context* context) override {
    std::string why;
    cohort_options_.seed = seed_;
    cohort_options_.subject = subject_;
    scan_.sampling = ds::ParseScanSampling(sampling_);
    scan_.pattern = ds::ParseSweepPattern(pattern_);
    scan_.tracker_pivot = ds::ParseTrackerPivot(tracker_pivot_);
    scan_.tracker_draw = ds::ParseTrackerDraw(tracker_draw_);
    cohort_options_.scan = scan_;
    if (!cohort_options_.IsValid(&why)) ThrowUsage(why);
    if (!write_.IsValid(&why)) ThrowUsage(why);
    Report& report = context->report;
    report["out"] = out_.string();
    report["seed"] = seed_;
    std::vector<ds::SyntheticSubject> subjects;
    std::vector<std::string> folders;
    {
      auto t = report.Stage("shapes");
      if (cohort_->parsed()) {
        report["mode"] = "cohort";
        subjects = ds::MakeCohortSubjects(cohort_options_);
      } else if (subject_cmd_->parsed()) {
        report["mode"] = "subject";
        subjects.push_back(ds::MakeSubjectWithPectus(subject_, seed_, index_, Pectus()));
      } else if (pair_->parsed()) {
        report["mode"] = "pair";
        const ds::SyntheticSubject pre = ds::MakeSubjectWithPectus(subject_, seed_, index_, Pectus());
        subjects = {pre, ds::GrowSubject(pre, growth_, "post")};
        subjects[0].name = "pre";
      } else {
        report["mode"] = "patient";
        subjects = PatientSubjects(&report);
      }
    }
    // A single subject goes straight into --out; several get a folder each.
    const bool single = subjects.size() == 1 && !cohort_->parsed() && !patient_->parsed();
    auto folder_of = [&](std::size_t i) { return single ? out_ : out_ / subjects[i].name; };
    // The subjects on the task farm (docs/cluster.md): each one scanned and its files written to the work
    // folder, then its record committed (bytes, points); the leader moves the files into the outputs.
    const TaskShare share = shard_.empty() ? TaskShare{} : ParseTaskShare(shard_);
    if (!share.whole() && (gather_ || context->runner->Processes() > 1))
      ThrowUsage("--shard runs one share on its own: not with --gather, nor under mpirun");
    SerialTaskRunner share_runner(share);
    TaskRunner& runner = share.whole() ? *context->runner : share_runner;
    const fs::path work = work_.empty() ? out_ / ".pectus-work" : fs::path(work_);
    const fs::path files = work / "synth", records = work / "synth-done";
    auto record_of = [&](std::size_t i) { return records / (subjects[i].name + ".json"); };
    const bool keep = resume_ || gather_ || !share.whole();
    if (runner.IsLeader() && !keep) RemoveSynthResults(work);
    runner.Barrier();
    std::vector<int> missing;
    for (std::size_t i = 0; i < subjects.size(); ++i) {
      if (!fs::exists(record_of(i))) missing.push_back(static_cast<int>(i));
    }
    if (gather_ && !missing.empty()) {
      std::string names;
      for (std::size_t k = 0; k < std::min<std::size_t>(missing.size(), 10); ++k)
        names += (k == 0 ? "" : ", ") + subjects[static_cast<std::size_t>(missing[k])].name;
      if (missing.size() > 10) names += " and " + std::to_string(missing.size() - 10) + " more";
      ThrowUsage("--gather: no share has made subject(s) " + names + " (they are not in " + work.string() +
                 "); run their shares, or the whole run with --resume");
    }
    // Subject i: scanned, its files written to the work folder, then its record (the commit).
    auto make_subject = [&](std::size_t i) {
      const fs::path subject_files = files / subjects[i].name;
      fs::remove_all(subject_files);  // what a killed run left of this subject
      const ds::StagePath stage = [&](const fs::path& target) {
        const fs::path path = subject_files / target.lexically_relative(folder_of(i));
        fs::create_directories(path.parent_path());
        return path;
      };
      const std::uint64_t scan_seed = ds::CohortScanSeed(seed_, static_cast<int>(i));
      const ds::ScannedSubject scanned =
          ds::ScanSubject(subjects[i], scan_, subject_.landmark_sd_mm, scan_seed);
      const std::uintmax_t bytes = ds::WriteSubjectFolder(scanned, folder_of(i), write_, stage);
      Eigen::Index points = 0;
      for (const ds::Sweep& s : scanned.scan.sweeps) points += s.cloud.size();
      if (preview_) ds::WriteSubjectPreview(scanned, folder_of(i) / "preview.png", stage);
      fs::create_directories(records);
      WriteFileAtomically(record_of(i), nlohmann::json{{"bytes", bytes}, {"points", points}}.dump() + "\n");
    };
    {
      auto t = report.Stage("scan_and_write");
      Progress progress("synthesising subjects", static_cast<std::int64_t>(missing.size()));
      runner.Run(missing, [&](int index) {
        const auto i = static_cast<std::size_t>(index);
        try {
          make_subject(i);
        } catch (const std::exception& e) {
          ThrowFailure(subjects[i].name + ": " + e.what());
        }
        progress.Advance();
      });
    }
    if (!share.whole()) {
      Info("synth: share " + shard_ + " done; its subjects are in " + work.string() +
           " (then: the same command with --gather)");
    }
    if (!runner.IsLeader() || !share.whole()) return;
    std::vector<std::uintmax_t> bytes(subjects.size(), 0);
    std::vector<Eigen::Index> points(subjects.size(), 0);
    for (std::size_t i = 0; i < subjects.size(); ++i) {
      const nlohmann::json r = ReadRecord(record_of(i));
      bytes[i] = r.at("bytes").get<std::uintmax_t>();
      points[i] = r.at("points").get<Eigen::Index>();
      MoveFilesInto(files / subjects[i].name,
                    [&](const fs::path& name) { return StageOutput(context, *this, folder_of(i) / name); });
    }
    if (cohort_->parsed()) WritePopulation(context);
    nlohmann::json list = nlohmann::json::array();
    std::uintmax_t total_bytes = 0;
    Eigen::Index total_points = 0;
    for (std::size_t i = 0; i < subjects.size(); ++i) {
      list.push_back({{"name", subjects[i].name},
                      {"origin", subjects[i].origin},
                      {"points", points[i]},
                      {"pectus_depth_mm", subjects[i].parameters.pectus.depth_mm}});
      total_bytes += bytes[i];
      total_points += points[i];
    }
    nlohmann::json index = {{"mode", report["mode"]},
                            {"seed", seed_},
                            {"frame", "mm; x to the subject's left, y up (superior), z anterior"},
                            {"subjects", list}};
    const std::filesystem::path index_file = out_ / (single ? "truth/synth.json" : "synth.json");
    WriteFileAtomically(StageOutput(context, *this, index_file), index.dump(2) + "\n");
    report["subjects"] = subjects.size();
    report["sweeps_per_subject"] = scan_.sweeps;
    report["points"] = total_points;
    report["bytes_written"] = total_bytes;
    Info("wrote " + std::to_string(subjects.size()) + " subject(s), " + std::to_string(total_points) +
         " scan points, to " + out_.string());
    RemoveSynthResults(work);  // every output is staged
  }

 private:
  void AddCommonOptions(CLI::App* sub) {
    sub->add_option("-o,--out", out_, "Output folder")->required();
    sub->add_option("--seed", seed_, "Random seed (same seed, same data)")->capture_default_str();
    sub->add_option("--sweeps", scan_.sweeps, "Sweeps per subject (3-8 usual)")->capture_default_str();
    sub->add_option("--overlap", scan_.overlap, "Fraction of a sweep's width shared with each neighbour")
        ->capture_default_str();
    sub->add_option("--spacing", scan_.spacing_mm, "Point spacing at a strip's centre (mm)")
        ->capture_default_str();
    sub->add_option("--noise", scan_.noise_mm, "Range noise along each ray, sd (mm)")->capture_default_str();
    sub->add_option("--tracker-deg", scan_.tracker_deg, "Rotation error of each sweep's pose (deg)")
        ->capture_default_str();
    sub->add_option("--tracker-mm", scan_.tracker_mm, "Translation error of each sweep's pose (mm)")
        ->capture_default_str();
    sub->add_option("--tracker-pivot", tracker_pivot_,
                    "Centre of the rotation error: wand (the wand's mean position) or lever (the tracker's "
                    "sensor, --tracker-lever off the skin along the line of sight)")
        ->capture_default_str()
        ->check(CLI::IsMember({"wand", "lever"}));
    sub->add_option("--tracker-lever", scan_.tracker_lever_mm,
                    "Sensor-to-skin distance of --tracker-pivot lever (mm)")
        ->capture_default_str();
    sub->add_option("--tracker-draw", tracker_draw_,
                    "exact: every sweep's error is the given size; uniform: drawn in [0, the given size]")
        ->capture_default_str()
        ->check(CLI::IsMember({"exact", "uniform"}));
    sub->add_option(
           "--tracker-skin", scan_.tracker_skin_mm,
           "If > 0: scale each sweep's error (rotation and translation in the ratio of --tracker-deg to "
           "--tracker-mm) to this RMS displacement of its points (mm)")
        ->capture_default_str();
    sub->add_option(
           "--sampling", sampling_,
           "grid (a range image: lines and columns) or random (points uniformly at random, same density)")
        ->capture_default_str()
        ->check(CLI::IsMember({"grid", "random"}));
    sub->add_option(
           "--pattern", pattern_,
           "Sweeps as vertical strips, horizontal strips, patches (a grid) or spiral (turns out from the "
           "sternum)")
        ->capture_default_str()
        ->check(CLI::IsMember({"vertical", "horizontal", "patches", "spiral"}));
    sub->add_option("--breathing", scan_.breathing_mm, "Breathing displacement between sweeps, up to (mm)")
        ->capture_default_str();
    sub->add_option("--holes", scan_.subject_holes, "Holes in every sweep (hair, dark skin)")
        ->capture_default_str();
    sub->add_option("--sweep-holes", scan_.sweep_holes, "Holes per sweep (occlusion, glare)")
        ->capture_default_str();
    sub->add_option("--hole-min", scan_.hole_min_mm, "Smallest hole diameter (mm)")->capture_default_str();
    sub->add_option("--hole-max", scan_.hole_max_mm, "Largest hole diameter (mm)")->capture_default_str();
    sub->add_option("--ragged", scan_.ragged_mm, "Wander of the strips' borders (mm)")->capture_default_str();
    sub->add_option("--outliers", scan_.outlier_fraction, "Fraction of outlier points")
        ->capture_default_str();
    sub->add_option("--standoff", scan_.standoff_mm, "Wand-to-skin distance (mm)")->capture_default_str();
    sub->add_option("--tremor-mm", scan_.tremor_mm, "Hand tremor of the wand's position (mm)")
        ->capture_default_str();
    sub->add_option("--tremor-deg", scan_.tremor_deg, "Hand tremor of the wand's direction (deg)")
        ->capture_default_str();
    sub->add_option("--max-incidence", scan_.max_incidence_deg, "No return beyond this incidence angle (deg)")
        ->capture_default_str();
    sub->add_option("--incidence-falloff", scan_.incidence_falloff, "Points kept with probability cos^this")
        ->capture_default_str();
    sub->add_option("--landmark-sd", subject_.landmark_sd_mm, "Placement error of landmarks.mrk.json (mm)")
        ->capture_default_str();
    sub->add_option("--pose-deg", subject_.pose_deg, "Random turn of each subject in the scanner frame (deg)")
        ->capture_default_str();
    sub->add_option("--pose-mm", subject_.pose_mm, "Random shift of each subject in the scanner frame (mm)")
        ->capture_default_str();
    sub->add_option("--truth-spacing", write_.truth_spacing_mm, "Edge length of the true meshes (mm)")
        ->capture_default_str();
    sub->add_flag("--no-chest-wall", no_chest_wall_, "Do not write truth/chest_wall.ply")
        ->each([this](const std::string&) { write_.chest_wall = false; });
    sub->add_flag("--no-sweep-truth", no_sweep_truth_, "Do not write truth/sweep_NN.ply")
        ->each([this](const std::string&) { write_.sweep_truth = false; });
    sub->add_option("--work", work_,
                    "Folder of the subjects' results until the outputs are written, on a file system every "
                    "rank sees (default: OUT/.pectus-work; emptied after a complete run)");
    sub->add_flag("--resume", resume_, "Keep the subjects made by a killed run and make only the rest");
    sub->add_option("--shard", shard_,
                    "K/N: only share K of N of the subjects (a job array without MPI), kept in the work "
                    "folder for --gather");
    sub->add_flag("--gather", gather_,
                  "Write the outputs from the subjects every share made (after --shard)");
    sub->add_flag("--preview", preview_,
                  "Also write preview.png (the subject, its sweeps coloured by sweep)");
  }

  // The subjects' files and records of a run on the farm, and the work folder if that empties it.
  static void RemoveSynthResults(const fs::path& work) {
    std::error_code ec;
    for (const char* part : {"synth", "synth-done"}) {
      fs::remove_all(work / part, ec);
      if (ec) ThrowFailure("cannot remove the subjects' results: " + ec.message(), (work / part).string());
    }
    if (fs::is_empty(work, ec)) fs::remove(work, ec);
  }

  void AddPectusOptions(CLI::App* sub) {
    sub->add_option("--pectus-depth", pectus_.depth_mm, "Depression depth (mm, 0-60; 0: none)")
        ->capture_default_str();
    sub->add_option("--pectus-type", pectus_type_, "saucer (broad) or cup (localised)")
        ->capture_default_str();
    sub->add_option("--pectus-x", pectus_.centre_x_mm, "Centre's offset to the subject's left (mm)")
        ->capture_default_str();
    sub->add_option("--pectus-y", pectus_.centre_y_mm, "Centre's height above the reference level (mm)")
        ->capture_default_str();
    sub->add_option("--asymmetry", pectus_.asymmetry, "Left half (1 + a) times as wide as the right (1 - a)")
        ->capture_default_str();
    sub->add_option("--torsion", pectus_.torsion_deg, "Sternal torsion (deg; + sinks the right side)")
        ->capture_default_str();
  }

  ds::PectusParameters Pectus() const {
    ds::PectusParameters p = pectus_;
    p.type = ds::ParsePectusType(pectus_type_);
    std::string why;
    if (!p.IsValid(&why)) ThrowUsage(why);
    return p;
  }

  std::vector<ds::SyntheticSubject> PatientSubjects(Report* report) {
    if (rows_.empty() && !all_rows_) ThrowUsage("synth patient: give --row N (repeatable) or --all");
    const std::vector<PatientTableRow> table = pectus::ReadPatientTable(table_);
    std::vector<PatientTableRow> chosen;
    if (all_rows_) {
      chosen = table;
    } else {
      for (int r : rows_) chosen.push_back(pectus::FindPatient(table, r, table_.string()));
    }
    std::vector<ds::SyntheticSubject> subjects(chosen.size());
#pragma omp parallel for schedule(dynamic)
    for (std::size_t i = 0; i < chosen.size(); ++i)
      subjects[i] = ds::MakePatientSubject(chosen[i], seed_, subject_);
    nlohmann::json fits = nlohmann::json::array();
    for (const ds::SyntheticSubject& s : subjects) {
      fits.push_back({{"name", s.name}, {"residual_mm", s.extra["fit_residual_mm"]}});
    }
    (*report)["patient_fits"] = fits;
    return subjects;
  }

  void WritePopulation(Context* context) {
    auto t = context->report.Stage("population");
    ds::ShapeGrid grid;
    if (std::sscanf(grid_.c_str(), "%dx%d", &grid.nu, &grid.nv) != 2 || grid.nu < 2 || grid.nv < 2 ||
        grid.nu > 1000 || grid.nv > 1000) {
      ThrowUsage("--grid must read NUxNV with 2 to 1000 vertices each way, e.g. 51x101");
    }
    if (modes_ < 1 || modes_ > 100) ThrowUsage("--modes must be within [1, 100]");
    const ds::TrueShapeStatistics st = ds::ComputeTrueShapeStatistics(subject_.population, grid, modes_);
    ds::WritePopulationFolder(subject_.population, st, out_ / "population",
                              [&](const std::filesystem::path& p) { return StageOutput(context, *this, p); });
    context->report["true_eigenvalues_mm2"] =
        std::vector<double>(st.eigenvalues.data(), st.eigenvalues.data() + st.eigenvalues.size());
  }

  CLI::App *cohort_ = nullptr, *subject_cmd_ = nullptr, *pair_ = nullptr, *patient_ = nullptr;
  std::filesystem::path out_;
  std::filesystem::path table_ = "../shared/datasets/patients/nuss_ct_parameters.csv";
  std::uint64_t seed_ = 7;
  int index_ = 0;
  int modes_ = 10;
  std::string grid_ = "51x101";
  std::vector<int> rows_;
  bool all_rows_ = false, no_chest_wall_ = false, no_sweep_truth_ = false, preview_ = false;
  std::string work_, shard_;
  bool resume_ = false, gather_ = false;
  ds::ScanOptions scan_;
  ds::SubjectOptions subject_;
  ds::CohortOptions cohort_options_;
  ds::SubjectWriteOptions write_;
  ds::GrowthOptions growth_;
  ds::PectusParameters pectus_;
  std::string pectus_type_ = "saucer";
  std::string sampling_ = "grid", pattern_ = "vertical", tracker_pivot_ = "wand", tracker_draw_ = "exact";
};

PECTUS_REGISTER_COMMAND(SynthCommand, 90);

}  // namespace
}  // namespace pectus::cli
