// pectus under mpirun: MPI started once per process (MpiSession, in pectus_main.cc) and the task farm over
// its ranks (MpiTaskRunner). Rank 0 hands out the tasks, largest first, one at a time to whichever rank asks
// (itself too: it works between hand-outs, from a thread that answers the others), and every task commits
// its own result file; the command then reads the results back in subject order on rank 0, so that the
// outputs are the bytes of the serial run whatever the number of ranks (docs/cluster.md). Built only when
// CMake finds MPI (PECTUS_HAVE_MPI); no MPI type appears here.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "apps/launched_by_mpi.h"
#include "shape/core/task_runner.h"

namespace pectus::cli {

/// MPI for the life of the object (MPI_Init_thread with MPI_THREAD_MULTIPLE, MPI_Finalize). One per process.
class MpiSession {
 public:
  MpiSession(int* argc, char*** argv);
  ~MpiSession();
  MpiSession(const MpiSession&) = delete;
  MpiSession& operator=(const MpiSession&) = delete;
  int rank() const { return rank_; }
  int size() const { return size_; }
  /// Ranks on this rank's node (this one included). Collective: every rank calls it.
  int NodeRanks() const;

 private:
  int rank_ = 0, size_ = 1;
};

/// The task farm over MPI_COMM_WORLD (see the file's comment).
class MpiTaskRunner : public TaskRunner {
 public:
  explicit MpiTaskRunner(const MpiSession& session)
      : rank_(session.rank()), size_(session.size()), node_ranks_(session.NodeRanks()) {}
  void Run(const std::vector<int>& order, const std::function<void(int)>& task) override;
  bool IsLeader() const override { return rank_ == 0; }
  /// This rank's threads times the ranks on its node: they wait (without spinning) while rank 0 works alone.
  int SerialThreads() const override;
  int Processes() const override { return size_; }
  void Barrier() override;
  std::string Describe() const override;
  /// Each rank computes its run of blocks in its threads, then MPI_Allgatherv (MPI_Gatherv to rank 0 if
  /// `leader_only`); every rank learns the first block error (MPI_Allreduce, then the failed rank's text).
  void ComputeBlocks(const std::vector<std::int64_t>& offsets,
                     const std::function<void(int, double*)>& compute, double* table,
                     bool leader_only = false) override;
  void Broadcast(void* data, std::int64_t bytes) override;

 private:
  // Rank 0's hand-out loop: answers each rank's request with the next task, or -1 when none is left,
  // until every rank had its -1; keeps the first task error a request carried.
  void HandOut(const std::vector<int>& order, std::string* first_error) const;
  int rank_, size_, node_ranks_;
};

}  // namespace pectus::cli
