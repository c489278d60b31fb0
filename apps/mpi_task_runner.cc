#include "apps/mpi_task_runner.h"

#include <mpi.h>
#include <omp.h>

#include <algorithm>
#include <chrono>
#include <exception>
#include <limits>
#include <thread>

#include "shape/core/error.h"

namespace pectus::cli {
namespace {

constexpr int kRequestTag = 17;  // worker -> rank 0: the previous task's error (empty: none), give me one
constexpr int kTaskTag = 18;     // rank 0 -> worker: a task index, or -1: no more

// Waits for `request` without spinning: a rank that is early for a collective (the others still computing
// their blocks, or rank 0 working alone) leaves its core to them, which matters whenever ranks share cores.
void WaitGently(MPI_Request* request) {
  int finished = 0;
  for (MPI_Test(request, &finished, MPI_STATUS_IGNORE); !finished;
       MPI_Test(request, &finished, MPI_STATUS_IGNORE))
    std::this_thread::sleep_for(std::chrono::microseconds(200));
}

}  // namespace

MpiSession::MpiSession(int* argc, char*** argv) {
  int provided = 0;
  MPI_Init_thread(argc, argv, MPI_THREAD_MULTIPLE, &provided);
  MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
  MPI_Comm_size(MPI_COMM_WORLD, &size_);
  if (provided < MPI_THREAD_MULTIPLE) {
    // Rank 0 hands out tasks from a thread of its own while it works; a library without thread support
    // cannot do that.
    MPI_Finalize();
    ThrowFailure("this MPI library does not support MPI_THREAD_MULTIPLE, which pectus needs under mpirun");
  }
}

MpiSession::~MpiSession() { MPI_Finalize(); }

int MpiSession::NodeRanks() const {
  MPI_Comm node;
  MPI_Comm_split_type(MPI_COMM_WORLD, MPI_COMM_TYPE_SHARED, rank_, MPI_INFO_NULL, &node);
  int size = 1;
  MPI_Comm_size(node, &size);
  MPI_Comm_free(&node);
  return size;
}

void MpiTaskRunner::HandOut(const std::vector<int>& order, std::string* first_error) const {
  std::size_t next = 0;
  int finished = 0;
  while (finished < size_) {
    int waiting = 0;
    MPI_Status status;
    MPI_Iprobe(MPI_ANY_SOURCE, kRequestTag, MPI_COMM_WORLD, &waiting, &status);
    if (!waiting) {  // poll gently: this thread shares rank 0's core with its work
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
      continue;
    }
    int length = 0;
    MPI_Get_count(&status, MPI_CHAR, &length);
    std::string error(static_cast<std::size_t>(length), '\0');
    MPI_Recv(error.data(), length, MPI_CHAR, status.MPI_SOURCE, kRequestTag, MPI_COMM_WORLD,
             MPI_STATUS_IGNORE);
    if (!error.empty() && first_error->empty()) *first_error = error;
    int task = -1;
    if (next < order.size()) {
      task = order[next++];
    } else {
      ++finished;
    }
    MPI_Send(&task, 1, MPI_INT, status.MPI_SOURCE, kTaskTag, MPI_COMM_WORLD);
  }
}

void MpiTaskRunner::Run(const std::vector<int>& order, const std::function<void(int)>& task) {
  std::string first_error;
  std::thread hand_out;
  if (rank_ == 0) hand_out = std::thread([&] { HandOut(order, &first_error); });
  std::string error;  // this rank's last task error, sent with its next request
  for (;;) {
    MPI_Send(error.data(), static_cast<int>(error.size()), MPI_CHAR, 0, kRequestTag, MPI_COMM_WORLD);
    error.clear();
    // Wait for the answer without spinning: rank 0 may be busy alone for a while (the model), and a
    // waiting rank should leave its core to it (TaskRunner::SerialThreads).
    int next = -1, answered = 0;
    MPI_Request request;
    MPI_Irecv(&next, 1, MPI_INT, 0, kTaskTag, MPI_COMM_WORLD, &request);
    for (MPI_Test(&request, &answered, MPI_STATUS_IGNORE); !answered;
         MPI_Test(&request, &answered, MPI_STATUS_IGNORE)) {
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    if (next < 0) break;
    try {
      task(next);
    } catch (const std::exception& e) {
      error = e.what();
      if (error.empty()) error = "task " + std::to_string(next) + " failed";
    }
  }
  if (hand_out.joinable()) hand_out.join();
  // Every rank learns the first error (and waits here until every task is done).
  int length = static_cast<int>(first_error.size());
  MPI_Bcast(&length, 1, MPI_INT, 0, MPI_COMM_WORLD);
  first_error.resize(static_cast<std::size_t>(length));
  MPI_Bcast(first_error.data(), length, MPI_CHAR, 0, MPI_COMM_WORLD);
  if (!first_error.empty()) ThrowFailure(first_error);
}

void MpiTaskRunner::Barrier() { MPI_Barrier(MPI_COMM_WORLD); }

void MpiTaskRunner::ComputeBlocks(const std::vector<std::int64_t>& offsets,
                                  const std::function<void(int, double*)>& compute, double* table,
                                  bool leader_only) {
  const auto blocks = static_cast<int>(offsets.size()) - 1;
  if (offsets.back() > std::numeric_limits<int>::max()) {
    ThrowFailure("a shared table of " + std::to_string(offsets.back()) +
                 " numbers is beyond what one MPI collective moves (2^31 - 1)");
  }
  // Rank r's run: blocks [first(r), first(r + 1)).
  auto first = [&](int r) { return static_cast<int>(static_cast<std::int64_t>(blocks) * r / size_); };
  std::string error;
  const int mine_begin = first(rank_), mine_end = first(rank_ + 1);
  std::vector<std::int64_t> mine(offsets.begin() + mine_begin, offsets.begin() + mine_end + 1);
  for (std::int64_t& o : mine) o -= offsets[static_cast<std::size_t>(mine_begin)];
  // A rank other than the leader keeps its run to itself when only the leader gathers the table.
  std::vector<double> own;
  if (leader_only && rank_ != 0) own.resize(static_cast<std::size_t>(mine.back()));
  double* const run = own.empty() && !(leader_only && rank_ != 0)
                          ? table + offsets[static_cast<std::size_t>(mine_begin)]
                          : own.data();
  try {
    TaskRunner::ComputeBlocks(
        mine, [&](int b, double* out) { compute(mine_begin + b, out); }, run);
  } catch (const std::exception& e) {
    error = e.what();
    if (error.empty()) error = "a block of a shared table failed";
  }
  // The first failed rank tells every rank its error.
  int failed = error.empty() ? size_ : rank_;
  MPI_Request request;
  MPI_Iallreduce(MPI_IN_PLACE, &failed, 1, MPI_INT, MPI_MIN, MPI_COMM_WORLD, &request);
  WaitGently(&request);
  if (failed < size_) {
    int length = static_cast<int>(error.size());
    MPI_Bcast(&length, 1, MPI_INT, failed, MPI_COMM_WORLD);
    error.resize(static_cast<std::size_t>(length));
    MPI_Bcast(error.data(), length, MPI_CHAR, failed, MPI_COMM_WORLD);
    ThrowFailure(error);
  }
  std::vector<int> counts(static_cast<std::size_t>(size_)), displacements(static_cast<std::size_t>(size_));
  for (int r = 0; r < size_; ++r) {
    displacements[r] = static_cast<int>(offsets[static_cast<std::size_t>(first(r))]);
    counts[r] = static_cast<int>(offsets[static_cast<std::size_t>(first(r + 1))]) - displacements[r];
  }
  if (!leader_only) {
    MPI_Iallgatherv(MPI_IN_PLACE, 0, MPI_DATATYPE_NULL, table, counts.data(), displacements.data(),
                    MPI_DOUBLE, MPI_COMM_WORLD, &request);
  } else if (rank_ == 0) {
    MPI_Igatherv(MPI_IN_PLACE, counts[0], MPI_DOUBLE, table, counts.data(), displacements.data(), MPI_DOUBLE,
                 0, MPI_COMM_WORLD, &request);
  } else {
    MPI_Igatherv(run, counts[rank_], MPI_DOUBLE, nullptr, nullptr, nullptr, MPI_DOUBLE, 0, MPI_COMM_WORLD,
                 &request);
  }
  WaitGently(&request);
}

void MpiTaskRunner::Broadcast(void* data, std::int64_t bytes) {
  // In pieces a collective's int count can hold.
  constexpr std::int64_t kPiece = std::int64_t{1} << 30;
  auto* p = static_cast<char*>(data);
  for (std::int64_t done = 0; done < bytes; done += kPiece) {
    // Waiting without spinning: the leader may work alone for a while before it sends (the model's
    // alignment, its eigen decomposition), and a waiting rank should leave its core to it.
    MPI_Request request;
    MPI_Ibcast(p + done, static_cast<int>(std::min(kPiece, bytes - done)), MPI_BYTE, 0, MPI_COMM_WORLD,
               &request);
    WaitGently(&request);
  }
}

int MpiTaskRunner::SerialThreads() const { return omp_get_max_threads() * node_ranks_; }

std::string MpiTaskRunner::Describe() const {
  return "MPI, " + std::to_string(size_) + " rank(s) of " + std::to_string(omp_get_max_threads()) +
         " thread(s)";
}

}  // namespace pectus::cli
