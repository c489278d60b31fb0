// pectus surrogate: the planner's fast stand-ins for the finite element solve (issue 14).
//   build  every patient of a table: the FE dataset (24 load cases) with each patient's exact response
//          basis, for `pectus plan --basis` and the trainer (load in milliseconds instead of seconds).
//   check  per patient, the exact response basis built through the plugin (interface version 2) against
//          the direct FE solve: the dissertation's 24 load cases and random (position, force) pairs, every
//          deformed bone vertex, skin vertex and skin landmark; the basis' size, rank and build time; the
//          cost of one real-time deform call and of one force for a lift, timed here on one thread.
//   evaluate  the learned emulator (for a patient without an FE run) left one patient out at a time over
//          a table, beside the nearest-patient and mean-response baselines; the figures, per patient
//          in the report.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <random>
#include <sstream>

#include "apps/command.h"
#include "apps/commands/plan_dataset.h"
#include "planner_plugin/host/planner_client.h"
#include "planner_plugin/host/planner_plugin_loader.h"
#include "shape/core/error.h"
#include "shape/core/log.h"
#include "shape/io/patient_table_io.h"

namespace pectus::cli {
namespace {

namespace fs = std::filesystem;
using namespace pectus::planner;
using Clock = std::chrono::steady_clock;

// The dissertation's load cases (§4.1.2): 3 bar positions (fractions of the sternal length) x 8 forces.
constexpr double kDissertationPositions[] = {0.65, 0.75, 0.85};
constexpr double kDissertationForces[] = {50, 70, 100, 200, 400, 800, 1500, 2000};

// "57,1,10" or "all" against the table.
std::vector<std::string> PatientList(const std::string& text, const fs::path& table) {
  std::vector<std::string> ids;
  if (text == "all") {
    for (const PatientTableRow& row : ReadPatientTable(table)) ids.push_back(std::to_string(row.patient));
    return ids;
  }
  std::stringstream in(text);
  for (std::string id; std::getline(in, id, ',');) {
    if (!id.empty()) ids.push_back(id);
  }
  if (ids.empty()) ThrowUsage("--patients '" + text + "' names no patient (ids separated by commas, or all)");
  return ids;
}

double Median(std::vector<double> values) {
  std::sort(values.begin(), values.end());
  return values.empty() ? 0.0 : values[values.size() / 2];
}

class SurrogateCommand : public Command {
 public:
  std::string Name() const override { return "surrogate"; }
  std::string Summary() const override {
    return "The planner's stand-ins for the FE solve: exact response bases (build, check) and the learned "
           "emulator (evaluate)";
  }
  std::string Example() const override {
    return "  pectus surrogate build --patient-table nuss_ct_parameters.csv -o bases.h5\n"
           "    (every patient's FE dataset and exact response basis, about 8 MB and 10 s each; then\n"
           "     pectus plan ... --basis bases.h5 takes the patient's basis instead of building it)\n"
           "  mpirun -n 16 pectus surrogate build --patient-table nuss_ct_parameters.csv -o bases.h5\n"
           "    (the patients shared out over 16 ranks, one thread each: the same bytes; docs/cluster.md)\n"
           "  pectus surrogate build ... -o bases.h5 --shard 2/8   (share 2 of 8 of a job array; then:)\n"
           "  pectus surrogate build ... -o bases.h5 --gather      (the shares' patients into bases.h5)\n"
           "  pectus surrogate build ... -o bases.h5 --resume      (after a killed run: only what is "
           "missing)\n"
           "  pectus surrogate check --patient-table nuss_ct_parameters.csv --patients 57,1,10,30,45 \\\n"
           "      --random 1000 --report check.json\n"
           "    (per patient: the basis against 24 + 1000 direct FE solves, its rank, size, build time and\n"
           "     the time of one full-surface update; fails if any point differs by more than --limit-mm)\n"
           "  pectus surrogate check --patient-table nuss_ct_parameters.csv --patients all --random 0\n"
           "  pectus surrogate evaluate --patient-table nuss_ct_parameters.csv --report emulator.json\n"
           "    (every patient left out in turn: the emulator fitted on the others predicts its 24 load "
           "cases\n"
           "     from its measurements, against its FE solution; about 4 minutes for 62 patients on 2 "
           "cores)\n"
           "  pectus surrogate evaluate --patient-table nuss_ct_parameters.csv --patients 1,2,3,4,5,6,7,8 "
           "\\\n"
           "      --cell-mm 12 --inputs ct-log";
  }
  void Configure(CLI::App* app) override {
    app->require_subcommand(1);
    build_ =
        app->add_subcommand("build", "The FE dataset of a patient table with every patient's response basis");
    build_->add_option("--patient-table", table_, "CSV of CT measurements (as `pectus plan`)")->required();
    build_->add_option("-o,--output", output_, "The dataset with bases (.h5), replaced only when complete")
        ->required();
    build_
        ->add_option("--tolerance-mm", tolerance_mm_,
                     "The bases' compression tolerance up to 2000 N, mm (default 0.003)")
        ->default_val(0.003)
        ->check(CLI::PositiveNumber);
    build_->add_option("--cell-mm", cell_mm_, "Mesh: cell length along the ribs, 2 to 20 mm (default 6)");
    build_->add_option("--plugin", plugin_path_, "The planner plugin (default: beside pectus)");
    farm_.Configure(build_, "patients", ".OUTPUT.pectus-work beside the output");
    build_->fallthrough();
    check_ =
        app->add_subcommand("check", "The exact response basis against the direct FE solve, per patient");
    check_->add_option("--patient-table", table_, "CSV of CT measurements (as `pectus plan`)")->required();
    check_->add_option("--patients", patients_, "Patient ids separated by commas, or all")->default_val("57");
    check_->add_option("--random", random_, "Random (position, force) pairs per patient besides the 24 cases")
        ->default_val(100)
        ->check(CLI::NonNegativeNumber);
    check_->add_option("--seed", seed_, "Seed of the random pairs")->default_val(1400);
    check_
        ->add_option("--tolerance-mm", tolerance_mm_,
                     "The basis' compression tolerance up to 2000 N, mm (the plugin's default: 0.003)")
        ->default_val(0.003)
        ->check(CLI::PositiveNumber);
    check_
        ->add_option("--limit-mm", limit_mm_,
                     "Fail if any point of any case differs from the direct solve by more than this, mm")
        ->default_val(0.01)
        ->check(CLI::PositiveNumber);
    check_->add_option("--evaluations", evaluations_, "Deform calls timed per patient")
        ->default_val(2000)
        ->check(CLI::PositiveNumber);
    check_->add_option("--cell-mm", cell_mm_, "Mesh: cell length along the ribs, 2 to 20 mm (default 6)");
    check_->add_option("--plugin", plugin_path_, "The planner plugin (default: beside pectus)");
    check_->fallthrough();  // --report, --threads, --quiet belong to `surrogate`
    evaluate_ = app->add_subcommand(
        "evaluate", "The learned emulator left one patient out at a time, against FE and two baselines");
    evaluate_->add_option("--patient-table", table_, "CSV of CT measurements (as `pectus plan`)")->required();
    evaluate_
        ->add_option("--patients", evaluate_patients_, "Patient ids separated by commas, or all (at least 6)")
        ->default_val("all");
    evaluate_
        ->add_option("--inputs", inputs_,
                     "What the emulator is given: map (the fitted patient map, default), ct, ct-log "
                     "(log lengths) or ct-log+map")
        ->check(CLI::IsMember({"map", "ct", "ct-log", "ct-log+map"}))
        ->default_val("map");
    evaluate_
        ->add_option("--scale", scale_, "Divided out before the components: lift (default), norm or none")
        ->check(CLI::IsMember({"lift", "norm", "none"}))
        ->default_val("lift");
    evaluate_->add_option("--components", components_, "Principal components per bar position at most")
        ->default_val(20)
        ->check(CLI::PositiveNumber);
    evaluate_->add_option("--explained", explained_, "Components kept to this fraction of the variance")
        ->default_val(0.9999)
        ->check(CLI::Range(1e-6, 1.0));
    evaluate_->add_flag("--learn-skin", learn_skin_,
                        "Learn the skin grid directly instead of the mesh's boundary nodes (worse; for "
                        "comparison)");
    evaluate_->add_option("--cell-mm", cell_mm_, "Mesh: cell length along the ribs, 2 to 20 mm (default 6)");
    evaluate_->add_option("--plugin", plugin_path_, "The planner plugin (default: beside pectus)");
    evaluate_->fallthrough();
  }
  std::vector<fs::path> Inputs() const override { return {table_}; }

  void Run(Context* context) override {
    const PlannerPlugin plugin = PlannerPlugin::Find(plugin_path_);
    context->report["plugin"] = {{"path", plugin.path().string()},
                                 {"description", plugin.description()},
                                 {"interface_version", plugin.api().version}};
    PectusPlannerOptions options = PluginDefaultOptions(plugin);
    if (cell_mm_ > 0) options.rib_cell_length_mm = cell_mm_;
    if (build_->parsed()) {
      Build(plugin, options, context);
      return;
    }
    if (evaluate_->parsed()) {
      Evaluate(plugin, options, context);
      return;
    }
    const std::vector<std::string> ids = PatientList(patients_, table_);
    Progress progress("surrogate check (patients)", static_cast<std::int64_t>(ids.size()));
    double worst = 0.0;
    std::string worst_patient;
    for (const std::string& id : ids) {
      const nlohmann::json row = Check(plugin, options, id);
      context->report["patients"].push_back(row);
      if (row["max_difference_mm"].get<double>() >= worst) {
        worst = row["max_difference_mm"].get<double>();
        worst_patient = id;
      }
      progress.Advance();
    }
    context->report["max_difference_mm"] = worst;
    context->report["limit_mm"] = limit_mm_;
    char line[300];
    std::snprintf(
        line, sizeof(line),
        "surrogate check: %zu patient(s), largest difference from the direct solve %.2e mm (patient "
        "%s; limit %.3g mm)",
        ids.size(), worst, worst_patient.c_str(), limit_mm_);
    Info(line);
    if (worst > limit_mm_) {
      ThrowFailure(std::string(line) +
                   ": the basis does not reproduce the FE solve; a smaller --tolerance-mm "
                   "keeps more modes");
    }
  }

 private:
  void Build(const PlannerPlugin& plugin, const PectusPlannerOptions& options, Context* context) {
    auto t = context->report.Stage("build");
    const PectusPlannerBasisOptions basis{tolerance_mm_, 2000.0};
    WriteDatasetOnFarm(context, *this, &farm_, plugin, table_, output_, options, &basis,
                       "FE dataset with response bases");
  }

  static nlohmann::json Json(const PectusPlannerEmulatorFigures& f,
                             const std::vector<PectusPlannerEmulatorPatient>& patients) {
    auto who = [&](std::int32_t i) -> nlohmann::json {
      if (i < 0 || static_cast<std::size_t>(i) >= patients.size()) return nullptr;
      return patients[static_cast<std::size_t>(i)].id;
    };
    nlohmann::json j = {{"cases", f.cases},
                        {"cases_lift_le_40mm", f.small_lift_cases},
                        {"skin_rms_mm_lift_le_40",
                         {{"mean", f.skin_rms_mean_mm},
                          {"max", f.skin_rms_max_mm},
                          {"fraction_le_1mm", f.skin_rms_within_1mm},
                          {"worst_patient", who(f.worst_skin_rms_patient)}}},
                        {"skin_p95_mm_lift_le_40",
                         {{"mean", f.skin_p95_mean_mm},
                          {"max", f.skin_p95_max_mm},
                          {"fraction_le_2mm", f.skin_p95_within_2mm}}},
                        {"relative_l2_all",
                         {{"mean", f.relative_l2_mean},
                          {"max", f.relative_l2_max},
                          {"fraction_le_5pc", f.relative_l2_within_5pc},
                          {"worst_patient", who(f.worst_relative_l2_patient)}}},
                        {"lift_error_mm_lift_le_40",
                         {{"mean", f.small_lift_error_mean_mm},
                          {"max", f.small_lift_error_max_mm},
                          {"fraction_le_1mm", f.small_lift_error_within_1mm}}},
                        {"lift_error_mm_all",
                         {{"mean", f.lift_error_mean_mm},
                          {"max", f.lift_error_max_mm},
                          {"worst_patient", who(f.worst_lift_patient)}}}};
    if (f.coverage_2sd >= 0) j["coverage_2sd"] = f.coverage_2sd;
    return j;
  }

  void Evaluate(const PlannerPlugin& plugin, const PectusPlannerOptions& options, Context* context) {
    auto t = context->report.Stage("evaluate");
    PectusPlannerEmulatorOptions emulator{};
    emulator.inputs = inputs_ == "map" ? 0 : inputs_ == "ct" ? 1 : inputs_ == "ct-log" ? 2 : 3;
    emulator.scale = scale_ == "lift" ? 0 : scale_ == "norm" ? 1 : 2;
    emulator.max_components = components_;
    emulator.explained_fraction = explained_;
    emulator.learn_skin = learn_skin_ ? 1 : 0;
    std::unique_ptr<Progress> progress;
    const EmulatorEvaluationReport r = EvaluatePlannerEmulator(
        plugin, table_, evaluate_patients_ == "all" ? std::string() : evaluate_patients_, options, emulator,
        [&](std::int64_t, std::int64_t total) {
          if (!progress) progress = std::make_unique<Progress>("emulator: FE solves, then folds", total);
          progress->Advance();
        });
    progress.reset();
    const PectusPlannerEmulatorEvaluation& s = r.summary;
    context->report["emulator"] = {{"inputs", inputs_},
                                   {"scale", scale_},
                                   {"max_components", components_},
                                   {"explained_fraction", explained_},
                                   {"learnt", learn_skin_ ? "skin grid" : "boundary nodes"}};
    context->report["evaluation"] = {{"patients", s.patients},
                                     {"positions", s.positions},
                                     {"forces", s.forces},
                                     {"skin_vertices", s.skin_vertices},
                                     {"training_set_seconds", s.training_set_seconds},
                                     {"evaluation_seconds", s.evaluation_seconds}};
    context->report["methods"] = {{"emulator", Json(s.emulator, r.patients)},
                                  {"nearest_patient", Json(s.nearest_patient, r.patients)},
                                  {"mean_response", Json(s.mean_response, r.patients)}};
    for (const PectusPlannerEmulatorPatient& p : r.patients) {
      nlohmann::json row = Json(p.emulator, {});
      for (auto& [key, value] : row.items()) {
        if (value.is_object()) value.erase("worst_patient");
      }
      row["patient"] = p.id;
      row["nearest_patient"] = p.nearest_patient;
      row["fit_s"] = p.fit_seconds;
      row["components_mean"] = p.components_mean;
      context->report["patients"].push_back(row);
    }
    auto line = [](const char* name, const PectusPlannerEmulatorFigures& f) {
      char text[400];
      std::snprintf(
          text, sizeof(text),
          "  %-16s skin RMS %.3f mm (max %.2f, %.1f%% <= 1 mm), p95 %.3f mm (max %.2f), relative L2 "
          "%.2f%% (max %.1f%%), lift error %.3f mm (max %.2f; all cases max %.2f)",
          name, f.skin_rms_mean_mm, f.skin_rms_max_mm, 100 * f.skin_rms_within_1mm, f.skin_p95_mean_mm,
          f.skin_p95_max_mm, 100 * f.relative_l2_mean, 100 * f.relative_l2_max, f.small_lift_error_mean_mm,
          f.small_lift_error_max_mm, f.lift_error_max_mm);
      return std::string(text);
    };
    char head[300];
    std::snprintf(
        head, sizeof(head),
        "surrogate evaluate: %lld patients left out one at a time, %lld cases (%lld with a lift <= 40 mm); "
        "2 sigma band covers %.1f%% of the emulator's errors",
        static_cast<long long>(s.patients), static_cast<long long>(s.emulator.cases),
        static_cast<long long>(s.emulator.small_lift_cases), 100 * s.emulator.coverage_2sd);
    Info(head);
    Info(line("emulator", s.emulator));
    Info(line("nearest patient", s.nearest_patient));
    Info(line("mean response", s.mean_response));
  }

  nlohmann::json Check(const PlannerPlugin& plugin, const PectusPlannerOptions& options,
                       const std::string& id) {
    PlannerClient planner(plugin, ReadPlannerPatient(plugin, table_, id), options);
    PectusPlannerBasisOptions basis_options{tolerance_mm_, 2000.0};
    auto start = Clock::now();
    const PectusPlannerBasisSummary basis = planner.BuildBasis(&basis_options);
    const double build_s = std::chrono::duration<double>(Clock::now() - start).count();
    // The cases: the dissertation's 24, then random ones over the sternum's length and the forces used.
    std::vector<BarPlacement> bars;
    for (double p : kDissertationPositions) {
      for (double f : kDissertationForces) bars.push_back({p, false, f});
    }
    std::mt19937 rng(seed_ + static_cast<unsigned>(std::hash<std::string>{}(id) % 100000));
    std::uniform_real_distribution<double> position(0.05, 0.95), force(10.0, 2000.0);
    for (int k = 0; k < random_; ++k) bars.push_back({position(rng), false, force(rng)});
    double worst = 0.0, worst_lift = 0.0;
    for (std::size_t first = 0; first < bars.size(); first += 64) {
      const std::vector<BarPlacement> block(
          bars.begin() + static_cast<std::ptrdiff_t>(first),
          bars.begin() + static_cast<std::ptrdiff_t>(std::min(first + 64, bars.size())));
      const std::vector<PlannedCase> direct = planner.Solve(block);
      const std::vector<PlannedCase> fast = planner.Deform(block);
      for (std::size_t k = 0; k < block.size(); ++k) {
        worst = std::max({worst, (direct[k].bone - fast[k].bone).cwiseAbs().maxCoeff(),
                          (direct[k].skin - fast[k].skin).cwiseAbs().maxCoeff()});
        for (std::size_t l = 0; l < direct[k].skin_landmarks.size(); ++l) {
          worst = std::max(
              worst, (direct[k].skin_landmarks.items[l].position - fast[k].skin_landmarks.items[l].position)
                         .cwiseAbs()
                         .maxCoeff());
        }
        worst_lift = std::max(worst_lift,
                              std::abs(direct[k].figures.sternum_lift_mm - fast[k].figures.sternum_lift_mm));
      }
    }
    // The real-time calls, timed one by one on this thread (the median of many; the first ones warm the
    // caches).
    const PectusPlannerInterface& api = plugin.api();
    PectusPlannerDeformer* deformer = nullptr;
    PectusPlannerStatus status{};
    ThrowIfFailed(api.create_deformer(planner.handle(), &deformer, &status), status);
    const std::unique_ptr<PectusPlannerDeformer, void (*)(PectusPlannerDeformer*)> own(deformer,
                                                                                       api.destroy_deformer);
    std::vector<double> bone(3 * static_cast<std::size_t>(planner.bone().num_vertices())),
        skin(3 * static_cast<std::size_t>(planner.skin().num_vertices()));
    std::vector<double> update_us, lift_us;
    std::uniform_real_distribution<double> level(0.5, 0.95);  // where the bar goes (the search's range)
    for (int k = 0; k < evaluations_; ++k) {
      const PectusPlannerBar bar = {level(rng), 0, force(rng)};
      auto t0 = Clock::now();
      const std::int32_t code =
          api.deform(deformer, &bar, bone.data(), skin.data(), nullptr, nullptr, &status);
      auto t1 = Clock::now();
      ThrowIfFailed(code, status);
      double f = 0.0;
      auto t2 = Clock::now();
      const std::int32_t lift_code = api.lift_force(deformer, &bar, 20.0, &f, &status);
      auto t3 = Clock::now();
      ThrowIfFailed(lift_code, status);
      update_us.push_back(1e6 * std::chrono::duration<double>(t1 - t0).count());
      lift_us.push_back(1e6 * std::chrono::duration<double>(t3 - t2).count());
    }
    return {{"patient", id},
            {"cases", bars.size()},
            {"max_difference_mm", worst},
            {"max_lift_difference_mm", worst_lift},
            {"rank", basis.rank},
            {"contact_nodes", basis.contact_nodes},
            {"points", basis.points},
            {"megabytes", static_cast<double>(basis.bytes) / 1e6},
            {"truncation_bound_mm", basis.truncation_bound_mm},
            {"build_s", build_s},
            {"update_median_us", Median(update_us)},
            {"lift_force_median_us", Median(lift_us)}};
  }

  TaskFarmOptions farm_;
  CLI::App* build_ = nullptr;
  CLI::App* check_ = nullptr;
  CLI::App* evaluate_ = nullptr;
  std::string table_, patients_ = "57", evaluate_patients_ = "all", plugin_path_, output_, inputs_ = "map",
                      scale_ = "lift";
  int components_ = 20;
  double explained_ = 0.9999;
  bool learn_skin_ = false;
  int random_ = 100, evaluations_ = 2000;
  unsigned seed_ = 1400;
  double tolerance_mm_ = 0.003, limit_mm_ = 0.01, cell_mm_ = 0;
};

PECTUS_REGISTER_COMMAND(SurrogateCommand, 125);

}  // namespace
}  // namespace pectus::cli
