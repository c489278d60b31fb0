// Running `pectus` on a task farm from a test (docs/cluster.md): under mpirun as root (CI), killed half
// way, and the output trees compared byte for byte.
#pragma once

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <sstream>
#include <string>
#include <thread>

namespace pectus::testing_support {

inline std::string ReadBytes(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream bytes;
  bytes << in.rdbuf();
  return bytes.str();
}

/// Every file under `folder` (path relative to it -> bytes), the work folder (.pectus-work) left out.
inline std::map<std::string, std::string> FilesUnder(const std::filesystem::path& folder) {
  std::map<std::string, std::string> files;
  for (const std::filesystem::directory_entry& e : std::filesystem::recursive_directory_iterator(folder)) {
    if (!e.is_regular_file()) continue;
    const std::string name = std::filesystem::relative(e.path(), folder).string();
    if (name.rfind(".pectus-work", 0) == 0) continue;
    files[name] = ReadBytes(e.path());
  }
  return files;
}

/// The files under `folder` held against `expected`, file for file: none missing, none different, no
/// other; `what` names the run in the failures.
template <typename Expect>
void ExpectSameFiles(const std::map<std::string, std::string>& expected,
                     const std::map<std::string, std::string>& files, const std::string& what, Expect fail) {
  for (const auto& [name, bytes] : expected) {
    const auto found = files.find(name);
    if (found == files.end()) {
      fail(what + ": " + name + " is missing");
    } else if (found->second != bytes) {
      fail(what + ": " + name + " differs from the serial run's");
    }
  }
  if (files.size() != expected.size()) fail(what + ": other files than the serial run's");
}

#ifdef PECTUS_MPIEXEC
/// The launcher of `ranks` MPI ranks. CI runs as root: Open MPI refuses that unless told, here for this
/// command only. Under the sanitizers, full stacks for LeakSanitizer (cmake/sanitizers/lsan.supp: Open
/// MPI's own leaks). Those full stacks make every allocation 3-5 times dearer (the slow unwinder: a
/// 4-patient FE dataset on 2 ranks took 56 s with them and 14 s without, 2026-11-29). With `check_leaks`
/// false the ranks run without LeakSanitizer, ASan's other checks kept: for a test whose ranks run code
/// its serial run leak-checks already. The task farm's own code stays leak-checked under mpirun by the
/// pipeline's and the cohort's cluster tests.
inline std::string MpiLauncher(int ranks, bool check_leaks = true) {
  return std::string("OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 ") +
         (check_leaks ? "ASAN_OPTIONS=\"$ASAN_OPTIONS:fast_unwind_on_malloc=0\" "
                      : "ASAN_OPTIONS=\"$ASAN_OPTIONS:detect_leaks=0\" ") +
         PECTUS_MPIEXEC " --oversubscribe -n " + std::to_string(ranks);
}
#endif

/// How KillWhen ended.
struct Killed {
  bool finished_first = false;  ///< the command ended before `ready` held: it could not be killed half way
  bool killed = false;          ///< SIGKILL ended it (no clean-up)
};

/// Runs `pectus ARGS` (output discarded) and kills it with SIGKILL as soon as `ready()` holds (polled every
/// 2 ms, for 5 minutes at most).
inline Killed KillWhen(const std::string& args, const std::function<bool()>& ready) {
  const std::string command = "exec " PECTUS_EXECUTABLE " " + args + " > /dev/null 2>&1";
  Killed out;
  const pid_t pid = fork();
  if (pid < 0) return out;
  if (pid == 0) {
    execl("/bin/sh", "sh", "-c", command.c_str(), static_cast<char*>(nullptr));
    _exit(127);
  }
  int status = 0;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::minutes(5);
  while (!ready() && std::chrono::steady_clock::now() < deadline) {
    if (waitpid(pid, &status, WNOHANG) == pid) {
      out.finished_first = true;
      return out;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  kill(pid, SIGKILL);
  if (waitpid(pid, &status, 0) == pid) out.killed = WIFSIGNALED(status);
  return out;
}

/// Committed files with extension `ext` directly in `folder`: hidden ones (an atomic write's temporary
/// file) left out; 0 if the folder does not exist.
inline std::size_t CountFiles(const std::filesystem::path& folder, const std::string& ext) {
  std::error_code ec;
  std::size_t n = 0;
  for (std::filesystem::directory_iterator it(folder, ec), end; !ec && it != end; it.increment(ec)) {
    if (it->path().extension() == ext && it->path().filename().string()[0] != '.') ++n;
  }
  return n;
}

}  // namespace pectus::testing_support
