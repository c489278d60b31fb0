// pectus command line: the options every command that runs its subjects (or patients) on the task farm
// shares (docs/cluster.md): --work, --resume, --shard K/N, --gather, and which runner they give.
#pragma once

#include <CLI/CLI.hpp>
#include <filesystem>
#include <memory>
#include <string>

#include "shape/core/task_runner.h"

namespace pectus::cli {

/// --work DIR, --resume, --shard K/N and --gather of one command.
class TaskFarmOptions {
 public:
  /// Adds the four options to `app`; `items` names the tasks' subjects in the help ("subjects",
  /// "patients"), `default_work` where the work folder is by default ("OUT/.pectus-work").
  void Configure(CLI::App* app, const std::string& items, const std::string& default_work);
  /// The runner the tasks run on: the command's (`runner`: its threads, or the MPI ranks), or with
  /// --shard a serial runner of that share alone. Throws Error(kUsage) for --shard with --gather or under
  /// mpirun. Call once, before the work.
  TaskRunner* Runner(TaskRunner* runner);
  /// True if this process writes the outputs: the runner's leader, and not a share.
  bool Leader(const TaskRunner& runner) const { return runner.IsLeader() && share_.whole(); }
  /// The work folder: --work, or `default_work`.
  std::filesystem::path Work(const std::filesystem::path& default_work) const {
    return work_.empty() ? default_work : std::filesystem::path(work_);
  }
  /// The results already in the work folder are kept (--resume, --gather, or a share).
  bool resume() const { return resume_ || gather_ || !share_.whole(); }
  bool gather() const { return gather_; }
  /// Only a share of the tasks (--shard): no outputs.
  bool share_only() const { return !share_.whole(); }
  const std::string& shard_text() const { return shard_; }

 private:
  std::string work_, shard_;
  bool resume_ = false, gather_ = false;
  TaskShare share_;
  std::unique_ptr<SerialTaskRunner> share_runner_;
};

}  // namespace pectus::cli
