// pectus command line: one subcommand per class, registered in pectus_main.cc.
#pragma once

#include <CLI/CLI.hpp>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "shape/core/atomic_file.h"
#include "shape/core/report.h"
#include "shape/core/task_runner.h"

namespace pectus::cli {

/// What every command gets to run with.
struct Context {
  Report report;              ///< what the command did; written to --report on success
  OutputTransaction outputs;  ///< stage every output here; committed only if Run() returns
  int threads = 1;            ///< --threads (already applied to OpenMP)
  /// Where per-subject tasks run: this process's threads, or the MPI ranks under mpirun. Only the
  /// runner's leader writes the report and commits the outputs.
  TaskRunner* runner = nullptr;
  /// The command's inputs, resolved at the first StageOutput, which refuses every output among them.
  std::optional<InputGuard> inputs;
};

/// One `pectus <name>` subcommand.
class Command {
 public:
  virtual ~Command() = default;
  /// Subcommand name ("info").
  virtual std::string Name() const = 0;
  /// One line for `pectus --help`.
  virtual std::string Summary() const = 0;
  /// Worked example(s) shown at the end of `pectus <name> --help`.
  virtual std::string Example() const = 0;
  /// Adds the command's own options and positionals to `app`.
  virtual void Configure(CLI::App* app) = 0;
  /// Does the work; throws pectus::Error on failure. Files named on the command line as inputs are
  /// returned by Inputs() so that no output may overwrite them.
  virtual void Run(Context* context) = 0;
  /// Paths this command reads (for refusing an output equal to an input).
  virtual std::vector<std::filesystem::path> Inputs() const { return {}; }
};

/// Registers a command factory at start-up; `order` sets its place in `pectus --help`.
/// Use once per command file: `PECTUS_REGISTER_COMMAND(InfoCommand, 10)`.
struct CommandRegistration {
  using Factory = std::unique_ptr<Command> (*)();
  CommandRegistration(int order, Factory factory);
};
/// The registered commands, made fresh, in help order.
std::vector<std::unique_ptr<Command>> MakeAllCommands();

#define PECTUS_REGISTER_COMMAND(CLASS, ORDER)                       \
  static const ::pectus::cli::CommandRegistration kRegister##CLASS( \
      ORDER, []() -> std::unique_ptr<::pectus::cli::Command> { return std::make_unique<CLASS>(); })

/// Stages `target` in the context's transaction after refusing to overwrite any input.
std::filesystem::path StageOutput(Context* context, const Command& command,
                                  const std::filesystem::path& target);

/// Moves `from` (a file, or a folder that replaces `target` whole) onto `target` when the context's
/// transaction commits, after refusing to overwrite any input (any under the folder).
void MoveOutputAtCommit(Context* context, const Command& command, const std::filesystem::path& from,
                        const std::filesystem::path& target);

}  // namespace pectus::cli
