// pectus: the command line. `pectus <command> --help` explains each command with an example.
#include <malloc.h>
#include <omp.h>
#include <sys/mman.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <Eigen/Core>
#include <algorithm>
#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <optional>
#include <thread>

#include "apps/command.h"
#include "apps/launched_by_mpi.h"
#include "shape/core/error.h"
#include "shape/core/log.h"
#include "shape/core/task_runner.h"
#ifdef PECTUS_HAVE_MPI
#include "apps/mpi_task_runner.h"
#endif

namespace pectus::cli {

std::filesystem::path StageOutput(Context* context, const Command& command,
                                  const std::filesystem::path& target) {
  if (!context->inputs) context->inputs.emplace(command.Inputs());
  context->inputs->Refuse(target);
  return context->outputs.Stage(target);
}

void MoveOutputAtCommit(Context* context, const Command& command, const std::filesystem::path& from,
                        const std::filesystem::path& target) {
  if (!context->inputs) context->inputs.emplace(command.Inputs());
  std::error_code ec;
  if (std::filesystem::is_directory(from, ec)) {
    context->inputs->RefuseFolder(target);
  } else {
    context->inputs->Refuse(target);
  }
  context->outputs.MoveAtCommit(from, target);
}

namespace {

std::vector<std::pair<int, CommandRegistration::Factory>>& Registry() {
  static std::vector<std::pair<int, CommandRegistration::Factory>> registry;
  return registry;
}

}  // namespace

CommandRegistration::CommandRegistration(int order, Factory factory) {
  Registry().emplace_back(order, factory);
}

std::vector<std::unique_ptr<Command>> MakeAllCommands() {
  auto entries = Registry();
  std::stable_sort(entries.begin(), entries.end(),
                   [](const auto& a, const auto& b) { return a.first < b.first; });
  std::vector<std::unique_ptr<Command>> commands;
  for (const auto& [order, factory] : entries) commands.push_back(factory());
  return commands;
}

namespace {

// An error on the terminal; under MPI each rank names itself but rank 0.
void PrintError(const Command& command, int rank, const char* message) {
  if (rank == 0) {
    std::fprintf(stderr, "pectus %s: error: %s\n", command.Name().c_str(), message);
  } else {
    std::fprintf(stderr, "pectus %s (rank %d): error: %s\n", command.Name().c_str(), rank, message);
  }
}

// A command allocates and frees arrays of megabytes several times (a scan's points, a k-d tree, ICP's
// per-point buffers). glibc would serve each above 128 KiB with a mapping of its own, faulted in 4 KiB at a
// time and unmapped on free: 9800 page faults and about 14 % of the CPU of `pectus register` on two
// 100k-point scans. Here they come from the heap instead, which keeps freed memory for the next array,
// grows 64 MiB at a time, and is given transparent huge pages where the kernel offers them on request
// (`madvise` mode): 1600 page faults (docs/benchmarks/registration.md, "Where a pair's time goes").
// `one_arena`: every thread allocates from that heap too. glibc gives each further thread an arena of its
// own, mapped without the advice, where a pair's fixed scan is read and its k-d tree built (on the
// second thread, register_command.cc): with one arena `pectus register` on two 127k-point chest scans
// took 0.12 s instead of 0.19 s wall, its system time 0.07 s down to 0.01 s, on a VM whose page faults
// are dear (AMD EPYC, 2 vCPU, 2026-11-29; docs/benchmarks/registration.md, "One heap for every thread").
// For the light commands only, whose threads allocate a few large arrays each: the full program's
// commands allocate small objects on many threads at once (Ceres, the task farm), which one arena's
// lock would serialise.
void TuneHeapForLargeArrays(bool one_arena) {
  constexpr int kMiB = 1 << 20;
  if (one_arena) mallopt(M_ARENA_MAX, 1);  // before any other thread allocates
  mallopt(M_MMAP_THRESHOLD, 256 * kMiB);
  mallopt(M_TRIM_THRESHOLD, 512 * kMiB);
  mallopt(M_TOP_PAD, 64 * kMiB);
  // Grow the heap by the pad now, and ask for huge pages over it.
  void* probe = std::malloc(kMiB);
  if (probe == nullptr) return;
  const auto page = static_cast<std::uintptr_t>(2 * kMiB);
  const auto begin = (reinterpret_cast<std::uintptr_t>(probe) + page - 1) & ~(page - 1);
  const auto end = reinterpret_cast<std::uintptr_t>(sbrk(0)) & ~(page - 1);
  if (end > begin) madvise(reinterpret_cast<void*>(begin), end - begin, MADV_HUGEPAGE);  // advice only
  std::free(probe);
}

#ifdef PECTUS_FULL_PROGRAM
// `pectus` runs the commands built into it (those needing only the scan libraries: apps/CMakeLists.txt)
// and hands every other command line to PECTUS_FULL_PROGRAM in its own folder, which has every command:
// `pectus --help`, any other command, and any command under mpirun (whose ranks the full program
// starts). The same arguments, the same exit code.
bool RunsHere(int argc, char** argv) {
  if (argc < 2 || LaunchedByMpi()) return false;
  for (const std::unique_ptr<Command>& command : MakeAllCommands()) {
    if (command->Name() == argv[1]) return true;
  }
  return false;
}

int RunFullProgram(char** argv) {
  std::error_code error;
  const std::filesystem::path self = std::filesystem::read_symlink("/proc/self/exe", error);
  const std::filesystem::path full =
      (error ? std::filesystem::path(argv[0]).parent_path() : self.parent_path()) / PECTUS_FULL_PROGRAM;
  execv(full.c_str(), argv);
  const char* command = argv[1] != nullptr ? argv[1] : "--help";
  std::fprintf(stderr, "pectus: error: cannot start %s, which runs `pectus %s`: %s\n", full.c_str(), command,
               std::strerror(errno));
  return 1;
}
#endif

// Exit codes (docs/errors.md): 0 success, 2 usage, 3 bad input, 1 any other failure.
int Main(int argc, char** argv) {
#ifdef PECTUS_FULL_PROGRAM
  if (!RunsHere(argc, argv)) return RunFullProgram(argv);
  TuneHeapForLargeArrays(/*one_arena=*/true);  // the light program: its commands only
#else
  TuneHeapForLargeArrays(/*one_arena=*/false);
#endif
  // Under mpirun (or srun) every rank runs this same command: MPI is started once here, rank 0 hands out
  // the subjects of the commands that farm them out (Context::runner), prints, and writes the outputs.
#ifdef PECTUS_HAVE_MPI
  std::optional<MpiSession> mpi;
  if (LaunchedByMpi()) mpi.emplace(&argc, &argv);
  const int rank = mpi ? mpi->rank() : 0;
  const bool under_mpi = mpi.has_value();
#else
  const int rank = 0;
  const bool under_mpi = false;
#endif
  CLI::App app{
      "pectus: handheld chest scans to clean surfaces, shape models and Nuss procedure plans.\n"
      "Units are millimetres. Run `pectus <command> --help` for a worked example.\n"
      "On a cluster, `mpirun -n N pectus pipeline ...` shares the subjects out over N ranks, one\n"
      "thread each unless --threads says otherwise (docs/cluster.md).",
      "pectus"};
  app.require_subcommand(1);
  app.set_version_flag("--version", std::string(PECTUS_VERSION));

  std::vector<std::unique_ptr<Command>> commands = MakeAllCommands();

  std::string report_path;
  int threads = 0;
  bool quiet = false;
  std::vector<std::pair<CLI::App*, Command*>> subs;
  for (auto& command : commands) {
    CLI::App* sub = app.add_subcommand(command->Name(), command->Summary());
    sub->footer("\nExample:\n" + command->Example());
    sub->add_option("--report", report_path, "Write what the command did (counts, figures, timings) as JSON");
    sub->add_option("--threads", threads, "Worker threads (default: all cores; under mpirun: 1 per rank)")
        ->check(CLI::NonNegativeNumber);
    sub->add_flag("-q,--quiet", quiet,
                  "No progress or warnings on the terminal (warnings still go to --report)");
    command->Configure(sub);
    subs.emplace_back(sub, command.get());
  }

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (rank != 0) return e.get_exit_code() == 0 ? 0 : 2;  // rank 0 prints the help or the error
    const int code = app.exit(e);
    return code == 0 ? 0 : 2;
  }

  SetQuiet(quiet || rank != 0);
  Context context;
  std::unique_ptr<TaskRunner> runner = std::make_unique<SerialTaskRunner>();
#ifdef PECTUS_HAVE_MPI
  if (mpi) runner = std::make_unique<MpiTaskRunner>(*mpi);
#endif
  context.runner = runner.get();
  const int all_cores = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  context.threads = threads > 0 ? threads : under_mpi ? 1 : all_cores;
  omp_set_num_threads(context.threads);
  // One thread means one: libraries that ask for their own team size (CHOLMOD's supernodal factorisation
  // asks for 4) run on this thread too, instead of waking threads that share its core.
  if (context.threads == 1) omp_set_max_active_levels(0);
  // Eigen's own threads stay off: it splits a large product by the thread count, and so its sums' order
  // (a 200-subject model's Gram matrix differed in the last bits between 1 and 2 threads). Pectus's loops
  // run in parallel instead, each item computed alone, so the bytes of every output do not depend on
  // --threads or the ranks (docs/cluster.md).
  Eigen::setNbThreads(1);
  for (auto& [sub, command] : subs) {
    if (!sub->parsed()) continue;
    try {
      context.report["command"] = command->Name();
      context.report["pectus_version"] = PECTUS_VERSION;
      context.report["threads"] = context.threads;
      context.report["processes"] = context.runner->Processes();
      // Only the leader (rank 0) writes: the report and every output.
      const bool leader = context.runner->IsLeader();
      std::filesystem::path report_stage;
      if (!report_path.empty() && leader) report_stage = StageOutput(&context, *command, report_path);
      command->Run(&context);
      if (!leader) return 0;
      if (!report_path.empty()) context.report.Write(report_stage);
      context.outputs.CommitAll();
      return 0;
    } catch (const Error& e) {
      PrintError(*command, rank, e.what());
      return static_cast<int>(e.kind());
    } catch (const std::bad_alloc&) {
      PrintError(*command, rank, "out of memory");
      return 1;
    } catch (const std::exception& e) {
      PrintError(*command, rank, e.what());
      return 1;
    }
  }
  return 2;
}

}  // namespace
}  // namespace pectus::cli

int main(int argc, char** argv) { return pectus::cli::Main(argc, argv); }
