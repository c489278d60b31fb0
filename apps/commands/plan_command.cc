// pectus plan: a Nuss procedure plan for one patient (dissertation §4.3, §5.5) through the planner plugin:
// the patient's ribcage from CT measurements, the bar's push solved by finite elements, the predicted
// chest scored against the average chest, two scenarios side by side and the best bar placement, in an
// HTML report. With --dataset, the dissertation's FE dataset of every patient of the table.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>

#include "apps/command.h"
#include "apps/commands/plan_dataset.h"
#include "planner_plugin/host/average_chest.h"
#include "planner_plugin/host/nuss_plan.h"
#include "planner_plugin/host/planner_client.h"
#include "planner_plugin/host/planner_plugin_loader.h"
#include "shape/core/error.h"
#include "shape/core/log.h"

namespace pectus::cli {
namespace {

namespace fs = std::filesystem;
using namespace pectus::planner;

// "0.85" (a fraction of the sternal length from the notch) or "140mm" / "140 mm".
BarPlacement ParseBarPosition(const std::string& text, double force_n, const std::string& option) {
  std::string number = text;
  bool mm = false;
  if (const auto at = number.find("mm"); at != std::string::npos && at + 2 == number.size()) {
    number = number.substr(0, at);
    mm = true;
  }
  std::size_t used = 0;
  double value = 0;
  try {
    value = std::stod(number, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  while (used < number.size() && number[used] == ' ') ++used;
  if (used != number.size() || number.empty() || !std::isfinite(value)) {
    ThrowUsage(option + " '" + text +
               "' is not a number (a fraction such as 0.85, or millimetres such as 140mm)");
  }
  if (!mm && (value < 0 || value > 1)) {
    ThrowUsage(option + " " + text + " is not a fraction of the sternal length in [0, 1]; write " + text +
               "mm for millimetres from the notch");
  }
  return {value, mm, force_n};
}

nlohmann::json MeasurementsJson(const PectusPlannerPatient& p, const PectusPlannerMeasurements& m) {
  return {{"ct",
           {{"width_mm", p.width_mm / p.magnification},
            {"depth_mm", p.depth_mm / p.magnification},
            {"sternal_length_mm", p.sternal_length_mm},
            {"depression_mm", p.depression_mm / p.magnification},
            {"haller_index", p.ct_haller_index}}},
          {"model",
           {{"width_mm", m.width_mm},
            {"depth_mm", m.depth_mm},
            {"sternal_length_mm", m.sternal_length_mm},
            {"depression_mm", m.depression_mm},
            {"torsion_deg", m.torsion_deg},
            {"inner_width_mm", m.inner_width_mm},
            {"sternum_to_spine_mm", m.sternum_to_spine_mm},
            {"haller_index", m.haller_index}}},
          {"fit",
           {{"converged", m.fit_converged != 0},
            {"iterations", m.fit_iterations},
            {"largest_residual_mm", m.fit_residual_mm}}},
          {"mesh",
           {{"nodes", m.nodes},
            {"quadratic_tets", m.tets},
            {"free_dofs", m.free_dofs},
            {"assembly_and_factorisation_s", m.factorization_seconds}}}};
}

class PlanCommand : public Command {
 public:
  std::string Name() const override { return "plan"; }
  std::string Summary() const override {
    return "Nuss procedure plan: patient ribcage from CT measurements, FE bar push, scores against the "
           "average chest";
  }
  std::string Example() const override {
    return "  pectus plan --patient-table nuss_ct_parameters.csv --patient 57 --model average.h5 \\\n"
           "      --bar-position 0.85 --force 200 --out plan57/ --report r.json\n"
           "    (scenario B is 20 mm nearer the notch unless --compare-position is given; the best placement "
           "is\n"
           "     searched unless --no-search; open plan57/report.html)\n"
           "  pectus plan --patient-table nuss_ct_parameters.csv --patient 57 --model average.h5 --out "
           "plan57/ \\\n"
           "      --basis bases.h5\n"
           "    (the search on the patient's stored response basis: `pectus surrogate build`)\n"
           "  pectus plan --patient-table nuss_ct_parameters.csv --dataset fem_dataset.h5 --report d.json\n"
           "    (all patients x 3 bar positions x 8 forces, the dissertation's FE dataset; docs/planner.md)\n"
           "  mpirun -n 16 pectus plan --patient-table nuss_ct_parameters.csv --dataset fem_dataset.h5\n"
           "    (the patients over 16 ranks, the same bytes; with --shard K/N then --gather, or --resume\n"
           "     after a killed run, as `pectus surrogate build`; docs/cluster.md)";
  }
  void Configure(CLI::App* app) override {
    app->add_option("--patient-table", table_,
                    "CSV of CT measurements (patient, width_mm, sternal_length_mm, "
                    "depth_mm, depression_mm[, haller_index, magnification, torsion_deg])")
        ->required();
    app->add_option("--patient", patient_, "The patient to plan (an id of the table)");
    app->add_option("--model", model_, "The average chest: a statismo shape model from `pectus model build`");
    app->add_option("--model-landmarks", model_landmarks_,
                    "Landmarks of the average chest (sternal_notch, xiphoid, "
                    "manubrium_centre), if the model file has none");
    app->add_option("--bar-position", position_,
                    "Where the bar meets the sternum: fraction of the sternal length "
                    "from the notch (0.85) or millimetres (140mm)")
        ->default_val("0.85");
    app->add_option("--force", force_n_,
                    "The bar's push, N (about 175 N in adolescents, over 200 N in adults, Weber 2006; "
                    "the report gives the force that lifts the sternum by its depression)")
        ->default_val(200.0)
        ->check(CLI::PositiveNumber);
    app->add_option("--compare-position", compare_,
                    "Scenario B's bar position (default: 20 mm nearer the notch)");
    app->add_option("--out", out_, "Folder for the plan: meshes (PLY), pictures (PNG), report.html");
    app->add_flag("!--no-search", search_, "Skip the search for the best bar position and force");
    app->add_option("--basis", basis_,
                    "Take the patient's response basis from this FE dataset (`pectus surrogate build`) "
                    "instead of building it");
    app->add_flag("--search-direct", search_direct_,
                  "Search with a direct FE solve per bar position instead of the exact response basis "
                  "(the same scores to 0.001 mm; the basis takes seconds to build, then answers any "
                  "position at once)");
    app->add_option("--search-positions", search_options_.positions, "Bar positions in the search grid")
        ->default_val(10);
    app->add_option("--search-from", search_options_.position_from,
                    "First bar position searched, fraction of the sternal length from the notch")
        ->default_val(0.5);
    app->add_option("--search-to", search_options_.position_to,
                    "Last bar position searched (default 0.95: lower would be the tip of the xiphoid)")
        ->default_val(0.95);
    app->add_option("--search-forces", search_options_.forces, "Forces in the search grid")->default_val(31);
    app->add_option("--search-max-force", search_options_.force_max_n, "Largest force searched, N")
        ->default_val(3000);
    app->add_option("--search-refinements", search_options_.golden_iterations,
                    "Golden-section steps refining the best grid cell (each shrinks it by 0.618)")
        ->default_val(16);
    app->add_option("--registration", registration_, "similarity (default) or rigid landmark registration")
        ->default_val("similarity")
        ->check(CLI::IsMember({"similarity", "rigid"}));
    app->add_option("--cartilage-modulus", cartilage_mpa_,
                    "Young's modulus of the costal cartilage, MPa (default 80: calibrated to the "
                    "force measured in vivo; 20: the dissertation's Table 1; docs/planner.md)");
    app->add_option("--cell-mm", cell_mm_,
                    "Mesh: cell length along the ribs, 2 to 20 mm (default 6; cartilages 4 to 6)");
    app->add_option("--soft-tissue-mm", soft_tissue_mm_,
                    "Skin: soft-tissue thickness over the bones, mm (default 15)");
    app->add_option("--dataset", dataset_, "Write the FE dataset of every patient of the table (HDF5)");
    farm_.Configure(app, "patients", ".DATASET.pectus-work beside the dataset; with --dataset");
    app->add_option("--plugin", plugin_path_,
                    "The planner plugin (default: beside pectus, or PECTUS_PLANNER_PLUGIN)");
  }
  std::vector<fs::path> Inputs() const override {
    std::vector<fs::path> in{table_};
    if (!model_.empty()) in.emplace_back(model_);
    if (!basis_.empty()) in.emplace_back(basis_);
    if (!model_landmarks_.empty()) in.emplace_back(model_landmarks_);
    return in;
  }

  void Run(Context* context) override {
    if (patient_.empty() && dataset_.empty())
      ThrowUsage("give --patient (a plan) or --dataset (all patients)");
    if (!patient_.empty() && (model_.empty() || out_.empty())) {
      ThrowUsage("a plan needs --model (the average chest) and --out (the plan's folder)");
    }
    const PlannerPlugin plugin = PlannerPlugin::Find(plugin_path_);
    context->report["plugin"] = {{"path", plugin.path().string()},
                                 {"description", plugin.description()},
                                 {"interface_version", plugin.api().version}};
    options_ = PluginDefaultOptions(plugin);
    if (cartilage_mpa_ > 0) options_.cartilage_youngs_modulus_mpa = cartilage_mpa_;
    if (cell_mm_ > 0) options_.rib_cell_length_mm = cell_mm_;
    if (soft_tissue_mm_ >= 0) options_.soft_tissue_mm = soft_tissue_mm_;
    if (!dataset_.empty()) Dataset(plugin, context);
    if (!patient_.empty()) Plan(plugin, context);
  }

 private:
  void Dataset(const PlannerPlugin& plugin, Context* context) {
    auto t = context->report.Stage("dataset");
    WriteDatasetOnFarm(context, *this, &farm_, plugin, table_, dataset_, options_, nullptr, "FE dataset");
  }

  void Plan(const PlannerPlugin& plugin, Context* context);

  std::string table_, patient_, model_, model_landmarks_, position_ = "0.85", compare_, out_, dataset_,
                                                          plugin_path_;
  std::string registration_ = "similarity";
  double force_n_ = 200, cartilage_mpa_ = 0, cell_mm_ = 0, soft_tissue_mm_ = -1;
  bool search_ = true;
  PlacementSearchOptions search_options_;
  bool search_direct_ = false;
  std::string basis_;
  PectusPlannerOptions options_{};
  TaskFarmOptions farm_;
};

void PlanCommand::Plan(const PlannerPlugin& plugin, Context* context) {
  Report& report = context->report;
  NussPlanOptions options;
  options.scenario_a = ParseBarPosition(position_, force_n_, "--bar-position");
  if (!compare_.empty()) options.scenario_b = ParseBarPosition(compare_, force_n_, "--compare-position");
  options.search = search_;
  options.search_options = search_options_;
  options.score.registration.similarity = registration_ == "similarity";
  std::string why;
  if (!options.search_options.IsValid(&why)) ThrowUsage("search: " + why);
  // Step 1: the average chest, before the (slower) patient model, so a bad model file fails fast.
  AverageChest average;
  {
    auto t = report.Stage("read_average_chest");
    average = LoadAverageChest(model_, model_landmarks_);
  }
  // Step 2: the patient's ribcage, meshed and factorised in the plugin.
  const PectusPlannerPatient patient = ReadPlannerPatient(plugin, table_, patient_);
  std::unique_ptr<PlannerClient> planner;
  {
    auto t = report.Stage("ribcage_fit_mesh_factorisation");
    planner = std::make_unique<PlannerClient>(plugin, patient, options_);
  }
  if (search_ && !search_direct_) {
    // The exact response basis, for the search: every position it tries costs a product, not a solve.
    auto t = report.Stage("response_basis");
    const PectusPlannerBasisSummary basis =
        basis_.empty() ? planner->BuildBasis() : planner->LoadBasis(basis_);
    report["response_basis"] = {{"rank", basis.rank},
                                {"contact_nodes", basis.contact_nodes},
                                {"points", basis.points},
                                {"megabytes", static_cast<double>(basis.bytes) / 1e6},
                                {"truncation_bound_mm", basis.truncation_bound_mm},
                                {"seconds", basis.seconds},
                                {"from", basis_.empty() ? "built" : basis_}};
  }
  report["patient"] = patient.id;
  const PectusPlannerOptions& o = planner->options();
  report["materials"] = {
      {"sternum",
       {{"youngs_modulus_mpa", o.sternum_youngs_modulus_mpa}, {"poisson_ratio", o.sternum_poisson_ratio}}},
      {"rib", {{"youngs_modulus_mpa", o.rib_youngs_modulus_mpa}, {"poisson_ratio", o.rib_poisson_ratio}}},
      {"costal_cartilage",
       {{"youngs_modulus_mpa", o.cartilage_youngs_modulus_mpa},
        {"poisson_ratio", o.cartilage_poisson_ratio}}}};
  report["ribcage"] = MeasurementsJson(patient, planner->measurements());
  report["average_chest"] = {
      {"model", model_}, {"vertices", average.mesh.num_vertices()}, {"landmarks", average.landmark_source}};
  // Step 3: the plan (force to lift, scenarios, search), then its files.
  const NussPlan plan = MakeNussPlan(*planner, average, options, &report);
  const nlohmann::json figures = plan.ToJson();
  for (const auto& [key, value] : figures.items()) report[key] = value;
  auto t = report.Stage("write");
  const auto written =
      WriteNussPlan(plan, *planner, average, plugin.description(), out_,
                    [&](const fs::path& target) { return StageOutput(context, *this, target); });
  for (const fs::path& file : written) report["outputs"].push_back(file.string());
  // A linear model far outside its range says so (and the report marks it): a lift beyond twice the
  // depression.
  const double depression = plan.depression_mm;
  for (const PlanScenario& s : plan.scenarios) {
    const double lift = s.solved.figures.sternum_lift_mm;
    if (lift > LinearRangeLiftMm(depression)) {
      char text[400];
      std::snprintf(
          text, sizeof(text),
          "scenario %s (%s) lifts the sternum by %.0f mm, %.1f times its depression of %.1f mm: the "
          "linear model is far outside its range (the force to lift by the depression there is "
          "%.0f N; docs/planner.md, 'Force to lift')",
          s.name.c_str(), s.solved.bar.Name().c_str(), lift, lift / std::max(depression, 1e-9), depression,
          depression / lift * s.solved.bar.force_n);
      Warn(text);
    }
  }
  if (plan.search && !SearchEdgeNote(*plan.search).empty()) Warn("search: " + SearchEdgeNote(*plan.search));
  Info("plan for patient " + std::string(patient.id) + ": " + plan.BriefReport() + "; report " +
       (fs::path(out_) / "report.html").string());
}

PECTUS_REGISTER_COMMAND(PlanCommand, 120);

}  // namespace
}  // namespace pectus::cli
