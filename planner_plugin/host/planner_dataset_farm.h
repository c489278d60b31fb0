// pectus planner host: the FE dataset (and the patients' response bases) on a task farm (docs/cluster.md).
// Each patient of the table is a task: the plugin builds it and commits it as a part file in the work
// folder (interface version 6, write_dataset_part), wherever the task runs; the leader then has the
// plugin assemble the parts in table order (assemble_dataset). The dataset is the same bytes for any
// runner: serial threads, MPI ranks, or shares of a job array gathered afterwards.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "planner_plugin/api/planner_api.h"
#include "planner_plugin/host/planner_plugin_loader.h"
#include "shape/core/task_runner.h"

namespace pectus::planner {

/// Where the patients run and where their parts are kept.
struct DatasetFarm {
  /// Runs the patients' tasks; nullptr: SerialTaskRunner (this process's threads).
  TaskRunner* runner = nullptr;
  /// Folder of the parts (`parts/ID.h5`, or `parts/ID.failed` holding the reason), on a file system every
  /// process sees. Required.
  std::filesystem::path work;
  /// Keep the parts already in `work` (a killed run, shares to gather) and make only the missing ones;
  /// false: they are removed first. The table and options must be those of the run that made them.
  bool resume = false;
  /// Stop after the parts (a share of a job array, gathered later): no dataset.
  bool parts_only = false;
  /// Every patient's part (or failure) must be in `work` already: Error(kUsage) naming those missing.
  bool gather = false;
};

/// One patient of the table, as the farm left it.
struct DatasetPatient {
  std::string id;
  bool ok = false;
  std::string error;    ///< why it failed (when not ok)
  double seconds = -1;  ///< wall time of its task (-1: not known, e.g. made by an older run)
  /// Of `seconds`, what its process did once before its first patient (the generic ribcage of the options:
  /// the task's time less the part's own, as the plugin times it); about 0 for later tasks; -1: not known.
  double setup_seconds = -1;
};

/// What the farm did (on the leader; other processes get only `built`).
struct DatasetFarmResult {
  std::vector<DatasetPatient> patients;   ///< in table order
  PectusPlannerDatasetSummary summary{};  ///< of the assembled dataset: its patients, load cases, nodes
  double assemble_seconds = 0.0;
  int built = 0;         ///< patients built by this run (the others' parts were there: --resume, --gather)
  bool written = false;  ///< the dataset was assembled at `output`
  std::vector<std::filesystem::path> made_here;  ///< the files this process committed in `work`
};

/// Builds the FE dataset of every patient of `table` on the farm and, on the leader, assembles it at
/// `output` from the patients that succeeded, in table order. With `basis` (nullptr: none) each
/// patient's exact response basis too. A patient that fails is recorded with its reason and the others
/// go on; the dataset is written without it (DatasetFarmResult::patients says which). `done(patient)` is
/// called as each task of this process ends (serialized). Throws Error(kFailure) if no patient succeeds,
/// or the machinery fails (a part that cannot be committed), Error(kUsage) for a gather with parts missing.
/// A collective on the farm's runner: a failure of the leader's assembly is thrown on every process.
DatasetFarmResult BuildPlannerDatasetOnFarm(const PlannerPlugin& plugin, const std::filesystem::path& table,
                                            const std::filesystem::path& output,
                                            const PectusPlannerOptions& options,
                                            const PectusPlannerBasisOptions* basis, const DatasetFarm& farm,
                                            const std::function<void(const DatasetPatient&)>& done = {});

/// Removes the parts BuildPlannerDatasetOnFarm kept in `work`, and `work` itself if that leaves it empty.
void RemoveDatasetParts(const std::filesystem::path& work);

/// RemoveDatasetParts on the farm, once the leader has the dataset (`remove`: the leader's word; false
/// keeps every part, e.g. when it could not stage the dataset): each process removes the files it made
/// (`result.made_here`), all at once, then the leader the rest and the folder. Freeing a part's blocks
/// takes the file system about 3 ms, so 62 ranks take one part's time where one process takes 62
/// (docs/cluster.md). A collective: every process of the farm's runner calls it. Returns this process's
/// seconds.
double RemoveDatasetPartsOnFarm(const DatasetFarm& farm, const DatasetFarmResult& result, bool remove);

}  // namespace pectus::planner
