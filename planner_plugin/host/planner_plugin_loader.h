// pectus planner host: finds and loads the planner plugin (a shared library) at run time, and refuses a
// plugin built for another interface version. The host side of planner_api.h.
#pragma once

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "planner_plugin/api/planner_api.h"

namespace pectus::planner {

/// File name of the plugin on this platform.
inline constexpr const char* kPlannerPluginFileName = "libpectus_planner.so";

/// Where the host looks for the plugin, in order: `explicit_path` if not empty (nothing else then); the
/// environment variable PECTUS_PLANNER_PLUGIN; beside the running executable, in ../lib and in
/// ../planner_plugin from it; the build tree's plugin (PECTUS_PLANNER_PLUGIN_DEFAULT, set at compile time).
std::vector<std::filesystem::path> PlannerPluginCandidates(const std::filesystem::path& explicit_path = {});

/// A loaded planner plugin. Its handle is released (dlclose) when the last copy goes; the library itself
/// stays mapped for the life of the process (RTLD_NODELETE: its OpenMP runtime cannot be unloaded).
class PlannerPlugin {
 public:
  /// Loads the plugin at `path` and checks its interface version. Throws Error(kBadInput) naming the file
  /// if it cannot be loaded, lacks the entry point, or implements another interface version (naming
  /// both versions).
  static PlannerPlugin Load(const std::filesystem::path& path);
  /// Loads the first existing candidate of PlannerPluginCandidates(explicit_path). Throws
  /// Error(kUsage) listing the places looked in if there is none.
  static PlannerPlugin Find(const std::filesystem::path& explicit_path = {});

  /// The function table (valid while this object lives).
  const PectusPlannerInterface& api() const { return *api_; }
  const std::filesystem::path& path() const { return path_; }
  /// The plugin's own description ("pectus planner 0.1.0 (...)").
  std::string description() const;

 private:
  PlannerPlugin(std::shared_ptr<void> handle, const PectusPlannerInterface* api, std::filesystem::path path);
  std::shared_ptr<void> handle_;
  const PectusPlannerInterface* api_ = nullptr;
  std::filesystem::path path_;
};

/// Checks an interface table: throws Error(kBadInput) naming `path` if its version differs from
/// PECTUS_PLANNER_INTERFACE_VERSION or its table is smaller than this host's. Separate from Load so that
/// the check can be tested with any table.
void CheckPlannerInterface(const PectusPlannerInterface* api, const std::filesystem::path& path);

}  // namespace pectus::planner
