// Runs the `pectus` binary built beside the tests, the way a user would, and captures what it printed.
#pragma once

#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <string>

namespace pectus::testing_support {

struct CliRun {
  int code = -1;       // exit status, -1 when the command could not run or was killed
  std::string output;  // stdout and stderr, interleaved
};

// Runs `command` through the shell.
inline CliRun RunShell(const std::string& command) {
  const std::string cmd = command + " 2>&1";
  CliRun run;
  FILE* pipe = ::popen(cmd.c_str(), "r");
  if (pipe == nullptr) return run;
  std::array<char, 4096> buf{};
  while (std::fgets(buf.data(), buf.size(), pipe) != nullptr) run.output += buf.data();
  const int status = ::pclose(pipe);
  run.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return run;
}

// `args` is appended to the executable's path and run through the shell; `launcher`, if any, comes before
// the path (`mpiexec -n 2`, environment variables).
inline CliRun Pectus(const std::string& args, const std::string& launcher = "") {
  return RunShell((launcher.empty() ? "" : launcher + " ") + std::string(PECTUS_EXECUTABLE) + " " + args);
}

}  // namespace pectus::testing_support
