// pectus command line: the FE dataset of a patient table on the task farm (docs/cluster.md), for
// `pectus plan --dataset` and `pectus surrogate build` (with the response bases).
#pragma once

#include <filesystem>

#include "apps/command.h"
#include "apps/task_farm_options.h"
#include "planner_plugin/host/planner_plugin_loader.h"

namespace pectus::cli {

/// Builds the dataset of every patient of `table` on the command's farm (`farm`: --work, --resume,
/// --shard, --gather) and, on the leader, stages it at `output` in the context's outputs. A patient that
/// fails is warned about (its id and reason) and left out; the others go on (as the pipeline's subjects).
/// Fills context->report["dataset"]: the dataset's figures, and per patient its task's wall time, or its
/// failure. The parts are removed once the dataset is staged. `what` names it in messages ("FE dataset").
void WriteDatasetOnFarm(Context* context, const Command& command, TaskFarmOptions* farm,
                        const planner::PlannerPlugin& plugin, const std::filesystem::path& table,
                        const std::filesystem::path& output, const PectusPlannerOptions& options,
                        const PectusPlannerBasisOptions* basis, const std::string& what);

}  // namespace pectus::cli
