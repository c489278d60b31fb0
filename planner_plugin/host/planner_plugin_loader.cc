#include "planner_plugin/host/planner_plugin_loader.h"

#include <dlfcn.h>

#include <cstdlib>
#include <system_error>

#include "shape/core/error.h"

namespace pectus::planner {
namespace fs = std::filesystem;

std::vector<fs::path> PlannerPluginCandidates(const fs::path& explicit_path) {
  if (!explicit_path.empty()) return {explicit_path};
  std::vector<fs::path> out;
  if (const char* env = std::getenv("PECTUS_PLANNER_PLUGIN"); env != nullptr && *env != '\0')
    out.emplace_back(env);
  std::error_code error;
  const fs::path exe = fs::read_symlink("/proc/self/exe", error);
  if (!error) {
    const fs::path dir = exe.parent_path();
    out.push_back(dir / kPlannerPluginFileName);
    out.push_back(dir.parent_path() / "lib" / kPlannerPluginFileName);
    out.push_back(dir.parent_path() / "planner_plugin" / kPlannerPluginFileName);
  }
#ifdef PECTUS_PLANNER_PLUGIN_DEFAULT
  out.emplace_back(PECTUS_PLANNER_PLUGIN_DEFAULT);
#endif
  return out;
}

void CheckPlannerInterface(const PectusPlannerInterface* api, const fs::path& path) {
  if (api == nullptr) ThrowBadInput(path.string(), "the planner plugin returned no interface table");
  if (api->version != PECTUS_PLANNER_INTERFACE_VERSION) {
    ThrowBadInput(
        path.string(),
        "the planner plugin implements interface version " + std::to_string(api->version) +
            ", but this pectus needs version " + std::to_string(PECTUS_PLANNER_INTERFACE_VERSION) +
            (api->version < PECTUS_PLANNER_INTERFACE_VERSION
                 ? " (the plugin is older: it lacks the calls added since, such as the real-time "
                   "deform call of version 2, the emulator's evaluation of version 3, the basis table of "
                   "version 4, the trainer of version 5, the FE dataset by parts of version 6 and the "
                   "parts' own times of version 7)"
                 : " (the plugin is newer than this pectus)") +
            "; use a plugin built with this pectus (or the pectus it was built with)");
  }
  if (api->struct_size < sizeof(PectusPlannerInterface)) {
    ThrowBadInput(path.string(), "the planner plugin's interface table has " +
                                     std::to_string(api->struct_size) + " bytes, this pectus expects " +
                                     std::to_string(sizeof(PectusPlannerInterface)));
  }
}

PlannerPlugin::PlannerPlugin(std::shared_ptr<void> handle, const PectusPlannerInterface* api, fs::path path)
    : handle_(std::move(handle)), api_(api), path_(std::move(path)) {}

PlannerPlugin PlannerPlugin::Load(const fs::path& path) {
  dlerror();
  // RTLD_LOCAL: the plugin's own copies of pectus's core functions never clash with the host's.
  // RTLD_NODELETE: the plugin stays mapped for the life of the process, as do the libraries it brings.
  // Those are not made to be unloaded: libgomp (through CHOLMOD) keeps its environment and thread pool,
  // and unmapping them leaves that memory unreachable (LeakSanitizer) or running threads without code.
  void* raw = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL | RTLD_NODELETE);
  if (raw == nullptr) {
    const char* why = dlerror();
    ThrowBadInput(path.string(),
                  std::string("cannot load the planner plugin: ") + (why ? why : "unknown reason"));
  }
  std::shared_ptr<void> handle(raw, [](void* h) { dlclose(h); });
  dlerror();
  void* symbol = dlsym(raw, PECTUS_PLANNER_ENTRY_POINT);
  if (symbol == nullptr) {
    ThrowBadInput(path.string(),
                  std::string("not a pectus planner plugin: no symbol '") + PECTUS_PLANNER_ENTRY_POINT + "'");
  }
  const auto entry = reinterpret_cast<PectusPlannerEntryFn>(symbol);
  const PectusPlannerInterface* api = entry();
  CheckPlannerInterface(api, path);
  return PlannerPlugin(std::move(handle), api, path);
}

PlannerPlugin PlannerPlugin::Find(const fs::path& explicit_path) {
  const std::vector<fs::path> candidates = PlannerPluginCandidates(explicit_path);
  std::string looked;
  for (const fs::path& candidate : candidates) {
    std::error_code error;
    if (fs::is_regular_file(candidate, error)) return Load(candidate);
    looked += (looked.empty() ? "" : ", ") + candidate.string();
  }
  ThrowUsage("the planner plugin (" + std::string(kPlannerPluginFileName) +
             ") was not found; looked in: " + looked +
             ". Build it (component planner_plugin), or name it with --plugin or PECTUS_PLANNER_PLUGIN");
}

std::string PlannerPlugin::description() const {
  return api_->description != nullptr ? api_->description : "pectus planner plugin";
}

}  // namespace pectus::planner
