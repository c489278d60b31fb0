// pectus: the task farm every per-subject command runs on (docs/cluster.md). A command splits its work into
// tasks, one per subject or patient, each of which commits its own result file atomically (AtomicOutput);
// the runner decides where each task runs: here, in OpenMP threads (SerialTaskRunner); on other machines,
// over MPI (apps/mpi_task_runner.h, built when MPI is found); or only a share of them (--shard K/N, for job
// arrays). Whatever runs where, the command then reads the results back in subject order, so its outputs
// are the same bytes for any runner.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace pectus {

/// Runs independent tasks, each identified by its index.
class TaskRunner {
 public:
  virtual ~TaskRunner() = default;
  /// Runs task(i) for every i of `order` (task indices, largest first when sizes are known), on this
  /// process and its peers, and returns when every task of every process is done. A task that throws
  /// does not stop the others; Run then throws Error(kFailure) with the first message, on every process.
  virtual void Run(const std::vector<int>& order, const std::function<void(int)>& task) = 0;
  /// True on the one process that gathers the results and writes the outputs (MPI rank 0).
  virtual bool IsLeader() const { return true; }
  /// Processes taking part (MPI ranks; 1 otherwise).
  virtual int Processes() const { return 1; }
  /// Waits until every process got here (a no-op on one process).
  virtual void Barrier() {}
  /// Threads the leader may use for work it does alone between two Run() calls (the model), while the
  /// other processes wait: its own, and under MPI those of the ranks on its node (they wait idle).
  virtual int SerialThreads() const;
  /// One line for logs and reports: "serial, 2 threads", "MPI, 3 ranks", "shard 2/3".
  virtual std::string Describe() const = 0;

  /// A table of numbers computed by every process together (a collective: every process calls it, with
  /// the same arguments). Block b is rows `offsets[b]` to `offsets[b + 1]` of the table (numbers, not
  /// rows, in `table`'s layout); compute(b, table + offsets[b]) fills it on exactly one process, in that
  /// process's threads, from inputs every process holds alike. The blocks are dealt in contiguous runs, one
  /// run per process, and then every process holds the whole table (only the leader if `leader_only`:
  /// then `table` may be null on the others).
  /// A block's numbers depend only on `compute`, so the table is the same whatever the processes. A block
  /// that throws: Error(kFailure) with its message, on every process.
  virtual void ComputeBlocks(const std::vector<std::int64_t>& offsets,
                             const std::function<void(int, double*)>& compute, double* table,
                             bool leader_only = false);
  /// The leader's `bytes` bytes at `data` to every process (a collective; a no-op on one process).
  virtual void Broadcast(void* /*data*/, std::int64_t /*bytes*/) {}
  /// The leader's `ok` (and, when false, its `why`) to every process: a process that worked alone tells
  /// the others whether to go on. Returns `ok` as the leader had it; the others get its `why`.
  bool BroadcastOutcome(bool ok, std::string* why);
};

/// Starts the calling thread's OpenMP worker threads now (an empty parallel region), so that its first
/// parallel loop does not wait for them. Call it where the thread would otherwise wait for other work
/// (a file read on another thread): on a virtual machine, the first region of a thread took 2-14 ms to
/// create its workers and wake an idle core, most of a 10 000-point ICP level (docs/registration.md,
/// "The workers started early").
void StartWorkerThreads();

/// Rows per block of a shared table of `rows` rows: an eighth of them (so that a small table is shared
/// among processes too), at least 1 and at most `most`. It depends on the table, never on the processes.
std::int64_t BlockRows(std::int64_t rows, std::int64_t most);

/// Offsets of the blocks of `block` rows of `width` numbers (the last may be shorter) over `rows`.
std::vector<std::int64_t> BlockOffsets(std::int64_t rows, std::int64_t block, std::int64_t width);

/// One share of the tasks: share `index` (1-based) of `count`.
struct TaskShare {
  int index = 1;
  int count = 1;
  /// True for the task at position `position` of the task list (positions dealt round-robin).
  bool Holds(int position) const { return position % count == index - 1; }
  bool whole() const { return count == 1; }
};

/// "K/N" (1 <= K <= N) to a share; throws Error(kUsage) naming the text otherwise.
TaskShare ParseTaskShare(const std::string& text);

/// The tasks in this process's threads (OpenMP, dynamic schedule, `order` handed out in turn), only those
/// of `share` (positions in the task list in ascending index order: a share is the same subjects whatever
/// the order).
class SerialTaskRunner : public TaskRunner {
 public:
  explicit SerialTaskRunner(TaskShare share = {}) : share_(share) {}
  void Run(const std::vector<int>& order, const std::function<void(int)>& task) override;
  std::string Describe() const override;
  const TaskShare& share() const { return share_; }

 private:
  TaskShare share_;
};

/// Names for a message about tasks not done: the first `shown` joined by ", ", then " and K more".
std::string NamesForMessage(const std::vector<std::string>& names, std::size_t shown = 10);

/// Task indices 0..sizes.size()-1, largest size first (ties by index), so that the longest tasks start
/// first and the last to finish are short.
std::vector<int> LargestFirst(const std::vector<double>& sizes);

}  // namespace pectus
