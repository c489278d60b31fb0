#include "apps/commands/plan_dataset.h"

#include <memory>

#include "planner_plugin/host/planner_dataset_farm.h"
#include "shape/core/error.h"
#include "shape/core/log.h"
#include "shape/io/patient_table_io.h"

namespace pectus::cli {

namespace fs = std::filesystem;

void WriteDatasetOnFarm(Context* context, const Command& command, TaskFarmOptions* farm,
                        const planner::PlannerPlugin& plugin, const fs::path& table, const fs::path& output,
                        const PectusPlannerOptions& options, const PectusPlannerBasisOptions* basis,
                        const std::string& what) {
  planner::DatasetFarm run;
  run.runner = farm->Runner(context->runner);
  run.work = farm->Work(output.parent_path() / ("." + output.filename().string() + ".pectus-work"));
  run.resume = farm->resume();
  run.parts_only = farm->share_only();
  run.gather = farm->gather();
  const bool leader = farm->Leader(*context->runner);
  const fs::path staged = leader ? StageOutput(context, command, output) : fs::path();  // refuses an input
  const auto rows = static_cast<std::int64_t>(ReadPatientTable(table).size());
  Info(what + ": " + std::to_string(rows) + " patients of " + table.string() + " (" + run.runner->Describe() +
       ")");
  planner::DatasetFarmResult result;
  {
    Progress progress(what + " (patients)", rows);
    result = planner::BuildPlannerDatasetOnFarm(plugin, table, staged, options, basis, run,
                                                [&](const planner::DatasetPatient& p) {
                                                  // the leader warns of every failure at the end
                                                  if (!p.ok && farm->share_only())
                                                    Warn("patient " + p.id + " failed: " + p.error);
                                                  progress.Advance();
                                                });
  }
  if (farm->share_only()) {
    Info(what + ": share " + farm->shard_text() + " done; its patients' parts are in " + run.work.string() +
         " (then: the same command with --gather)");
    return;
  }
  if (!leader) {  // the leader has the dataset: remove this process's parts with the others
    planner::RemoveDatasetPartsOnFarm(run, result, true);
    return;
  }
  nlohmann::json patients = nlohmann::json::array(), failed = nlohmann::json::array();
  double seconds = 0.0;
  for (const planner::DatasetPatient& p : result.patients) {
    nlohmann::json row = {{"patient", p.id}, {"ok", p.ok}};
    if (p.seconds >= 0) {
      row["seconds"] = p.seconds;
      seconds += p.seconds;
    } else {
      row["seconds"] = nullptr;
    }
    if (p.setup_seconds >= 0) row["setup_seconds"] = p.setup_seconds;  // its process's first task
    if (!p.ok) {
      row["error"] = p.error;
      failed.push_back(p.id);
      Warn("patient " + p.id + " is not in the " + what + ": " + p.error);
    }
    patients.push_back(row);
  }
  std::error_code error;
  const auto bytes = fs::file_size(staged, error);
  const PectusPlannerDatasetSummary& s = result.summary;
  context->report["dataset"] = {{"path", output.string()},
                                {"patients", s.patients},
                                {"failed", failed},
                                {"built_by_this_run", result.built},
                                {"load_cases", s.load_cases},
                                {"results", s.results},
                                {"surface_nodes", s.surface_nodes},
                                {"seconds", seconds},
                                {"assemble_seconds", result.assemble_seconds},
                                {"megabytes", error ? 0.0 : static_cast<double>(bytes) / 1e6},
                                {"runner", run.runner->Describe()},
                                {"per_patient", patients}};
  Info(what + ": " + std::to_string(s.patients) + " patients x " + std::to_string(s.load_cases) +
       " load cases = " + std::to_string(s.results) + " results in " + output.string() +
       (failed.empty() ? "" : " (" + std::to_string(failed.size()) + " failed, left out)"));
  // The dataset is staged: the parts are no longer needed; each process removes its own.
  context->report["dataset"]["remove_parts_seconds"] = planner::RemoveDatasetPartsOnFarm(run, result, true);
}

}  // namespace pectus::cli
