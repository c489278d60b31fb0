#include "shape/core/task_runner.h"

#include <omp.h>

#include <algorithm>
#include <exception>
#include <numeric>

#include "shape/core/error.h"

namespace pectus {

TaskShare ParseTaskShare(const std::string& text) {
  TaskShare share;
  const std::size_t slash = text.find('/');
  try {
    std::size_t end_k = 0, end_n = 0;
    if (slash == std::string::npos) throw std::invalid_argument("no slash");
    share.index = std::stoi(text.substr(0, slash), &end_k);
    share.count = std::stoi(text.substr(slash + 1), &end_n);
    if (end_k != slash || end_n != text.size() - slash - 1) throw std::invalid_argument("trailing text");
  } catch (const std::exception&) {
    ThrowUsage("--shard '" + text + "': expected K/N, share K of N (1 <= K <= N)");
  }
  if (share.count < 1 || share.index < 1 || share.index > share.count)
    ThrowUsage("--shard '" + text + "': expected K/N with 1 <= K <= N");
  return share;
}

void SerialTaskRunner::Run(const std::vector<int>& order, const std::function<void(int)>& task) {
  std::vector<int> mine;
  for (int i : order) {
    if (share_.Holds(i)) mine.push_back(i);
  }
  std::string first_error;
  const auto n = static_cast<int>(mine.size());
  auto run = [&](int k) {
    try {
      task(mine[static_cast<std::size_t>(k)]);
    } catch (const std::exception& e) {
#pragma omp critical(pectus_task_runner_error)
      if (first_error.empty()) first_error = e.what();
    }
  };
  if (n <= 1 || omp_get_max_threads() == 1) {
    // One thread: the tasks at the top level, so that their own parallel loops (CHOLMOD's in the planner
    // plugin) run on OpenMP's pooled team. Inside a parallel region, even of one thread, each of them
    // would start and end a team of its own (threads made, spinning, unmade: 4x the time of a patient).
    for (int k = 0; k < n; ++k) run(k);
  } else {
    // Several threads: the tasks are the parallelism; their own loops run in the task's thread.
    const int levels = omp_get_max_active_levels();
    omp_set_max_active_levels(1);
#pragma omp parallel for schedule(dynamic, 1)
    for (int k = 0; k < n; ++k) run(k);
    omp_set_max_active_levels(levels);
  }
  if (!first_error.empty()) ThrowFailure(first_error);
}

int TaskRunner::SerialThreads() const { return omp_get_max_threads(); }

void TaskRunner::ComputeBlocks(const std::vector<std::int64_t>& offsets,
                               const std::function<void(int, double*)>& compute, double* table, bool) {
  const auto blocks = static_cast<int>(offsets.size()) - 1;
  std::string first_error;
#pragma omp parallel for schedule(dynamic, 1) if (blocks > 1)
  for (int b = 0; b < blocks; ++b) {
    try {
      compute(b, table + offsets[static_cast<std::size_t>(b)]);
    } catch (const std::exception& e) {
#pragma omp critical(pectus_task_runner_error)
      if (first_error.empty()) first_error = e.what();
    }
  }
  if (!first_error.empty()) ThrowFailure(first_error);
}

bool TaskRunner::BroadcastOutcome(bool ok, std::string* why) {
  std::int64_t header[2] = {ok ? 1 : 0, static_cast<std::int64_t>(why->size())};
  Broadcast(header, sizeof header);
  if (header[0] == 1) return true;
  why->resize(static_cast<std::size_t>(header[1]));
  Broadcast(why->data(), header[1]);
  return false;
}

void StartWorkerThreads() {
  if (omp_get_max_threads() < 2) return;
  // Each thread says it ran: an empty region would be compiled away.
  std::vector<int> ran(static_cast<std::size_t>(omp_get_max_threads()), 0);
#pragma omp parallel
  ran[static_cast<std::size_t>(omp_get_thread_num())] = 1;
}

std::int64_t BlockRows(std::int64_t rows, std::int64_t most) {
  return std::clamp<std::int64_t>((rows + 7) / 8, 1, std::max<std::int64_t>(1, most));
}

std::vector<std::int64_t> BlockOffsets(std::int64_t rows, std::int64_t block, std::int64_t width) {
  std::vector<std::int64_t> offsets{0};
  for (std::int64_t r = 0; r < rows; r += block) offsets.push_back(std::min(rows, r + block) * width);
  return offsets;
}

std::string SerialTaskRunner::Describe() const {
  std::string s = "one process, " + std::to_string(omp_get_max_threads()) + " thread(s)";
  if (!share_.whole()) s += ", share " + std::to_string(share_.index) + "/" + std::to_string(share_.count);
  return s;
}

std::string NamesForMessage(const std::vector<std::string>& names, std::size_t shown) {
  std::string text;
  for (std::size_t k = 0; k < std::min(names.size(), shown); ++k) text += (k == 0 ? "" : ", ") + names[k];
  if (names.size() > shown) text += " and " + std::to_string(names.size() - shown) + " more";
  return text;
}

std::vector<int> LargestFirst(const std::vector<double>& sizes) {
  std::vector<int> order(sizes.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return sizes[a] > sizes[b]; });
  return order;
}

}  // namespace pectus
