#include "apps/task_farm_options.h"

#include "shape/core/error.h"

namespace pectus::cli {

void TaskFarmOptions::Configure(CLI::App* app, const std::string& items, const std::string& default_work) {
  app->add_option("--work", work_,
                  "Folder of the " + items +
                      "' results, committed as each finishes, on a file system every "
                      "rank sees (default: " +
                      default_work + "; emptied after a complete run)");
  app->add_flag("--resume", resume_, "Keep the " + items + "' results of a killed run and do only the rest");
  app->add_option("--shard", shard_,
                  "K/N: only share K of N of the " + items +
                      " (a job array without MPI), kept in the work "
                      "folder for --gather");
  app->add_flag("--gather", gather_,
                "The shares' results to every output; fails naming the " + items + " no share did");
}

TaskRunner* TaskFarmOptions::Runner(TaskRunner* runner) {
  share_ = shard_.empty() ? TaskShare{} : ParseTaskShare(shard_);
  if (share_.whole()) return runner;
  if (gather_ || runner->Processes() > 1)
    ThrowUsage("--shard runs one share on its own: not with --gather, nor under mpirun");
  share_runner_ = std::make_unique<SerialTaskRunner>(share_);
  return share_runner_.get();
}

}  // namespace pectus::cli
