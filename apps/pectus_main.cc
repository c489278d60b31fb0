// pectus: the command line. `pectus <command> --help` explains each command with an example.
#include <omp.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdio>
#include <thread>

#include "apps/command.h"
#include "shape/core/error.h"
#include "shape/core/log.h"

namespace pectus::cli {

std::filesystem::path StageOutput(Context* context, const Command& command, const std::filesystem::path& target) {
  RefuseOverwritingInputs(target, command.Inputs());
  return context->outputs.Stage(target);
}

namespace {

std::vector<std::pair<int, CommandRegistration::Factory>>& Registry() {
  static std::vector<std::pair<int, CommandRegistration::Factory>> registry;
  return registry;
}

}  // namespace

CommandRegistration::CommandRegistration(int order, Factory factory) { Registry().emplace_back(order, factory); }

std::vector<std::unique_ptr<Command>> MakeAllCommands() {
  auto entries = Registry();
  std::stable_sort(entries.begin(), entries.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  std::vector<std::unique_ptr<Command>> commands;
  for (const auto& [order, factory] : entries) commands.push_back(factory());
  return commands;
}

namespace {

// Exit codes (docs/errors.md): 0 success, 2 usage, 3 bad input, 1 any other failure.
int Main(int argc, char** argv) {
  CLI::App app{"pectus: handheld chest scans to clean surfaces, shape models and Nuss procedure plans.\n"
               "Units are millimetres. Run `pectus <command> --help` for a worked example.",
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
    sub->add_option("--threads", threads, "Worker threads (default: all cores)")->check(CLI::NonNegativeNumber);
    sub->add_flag("-q,--quiet", quiet, "No progress or warnings on the terminal (warnings still go to --report)");
    command->Configure(sub);
    subs.emplace_back(sub, command.get());
  }

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return code == 0 ? 0 : 2;
  }

  SetQuiet(quiet);
  Context context;
  context.threads = threads > 0 ? threads : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  omp_set_num_threads(context.threads);
  for (auto& [sub, command] : subs) {
    if (!sub->parsed()) continue;
    try {
      context.report["command"] = command->Name();
      context.report["pectus_version"] = PECTUS_VERSION;
      context.report["threads"] = context.threads;
      std::filesystem::path report_stage;
      if (!report_path.empty()) report_stage = StageOutput(&context, *command, report_path);
      command->Run(&context);
      if (!report_path.empty()) context.report.Write(report_stage);
      context.outputs.CommitAll();
      return 0;
    } catch (const Error& e) {
      std::fprintf(stderr, "pectus %s: error: %s\n", command->Name().c_str(), e.what());
      return static_cast<int>(e.kind());
    } catch (const std::bad_alloc&) {
      std::fprintf(stderr, "pectus %s: error: out of memory\n", command->Name().c_str());
      return 1;
    } catch (const std::exception& e) {
      std::fprintf(stderr, "pectus %s: error: %s\n", command->Name().c_str(), e.what());
      return 1;
    }
  }
  return 2;
}

}  // namespace
}  // namespace pectus::cli

int main(int argc, char** argv) { return pectus::cli::Main(argc, argv); }
