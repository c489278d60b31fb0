#include "planner_plugin/host/planner_plugin_loader.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>

#include "shape/core/error.h"

namespace pectus::planner {
namespace {
namespace fs = std::filesystem;

// The error kind and message of `f`, which must throw pectus::Error.
template <typename F>
std::pair<ErrorKind, std::string> Failure(F&& f) {
  try {
    f();
  } catch (const Error& e) {
    return {e.kind(), e.what()};
  }
  ADD_FAILURE() << "expected a pectus::Error";
  return {ErrorKind::kFailure, ""};
}

TEST(PlannerPluginLoader, LoadsThePluginOfThisInterfaceVersion) {
  const PlannerPlugin plugin = PlannerPlugin::Load(PECTUS_PLANNER_PLUGIN_PATH);
  EXPECT_EQ(plugin.api().version, PECTUS_PLANNER_INTERFACE_VERSION);
  EXPECT_NE(plugin.description().find("pectus planner"), std::string::npos);
  // Copies share the loaded library.
  const PlannerPlugin copy = plugin;
  EXPECT_EQ(&copy.api(), &plugin.api());
}

TEST(PlannerPluginLoader, RefusesAPluginOfAnotherVersionNamingBoth) {
  // A plugin of interface 1 (before the basis and the deform call).
  const auto [kind, message] = Failure([] { PlannerPlugin::Load(PECTUS_PLANNER_FAKE_V1_PATH); });
  EXPECT_EQ(kind, ErrorKind::kBadInput);
  EXPECT_NE(message.find("interface version 1"), std::string::npos) << message;
  EXPECT_NE(message.find("needs version " + std::to_string(PECTUS_PLANNER_INTERFACE_VERSION)),
            std::string::npos)
      << message;
  EXPECT_NE(message.find("older"), std::string::npos) << message;
  EXPECT_NE(message.find(fs::path(PECTUS_PLANNER_FAKE_V1_PATH).filename().string()), std::string::npos)
      << message;
  // The same check on any table: a table too small for this host is refused too.
  PectusPlannerInterface small{};
  small.version = PECTUS_PLANNER_INTERFACE_VERSION;
  small.struct_size = 16;
  EXPECT_THROW(CheckPlannerInterface(&small, "small.so"), Error);
  EXPECT_THROW(CheckPlannerInterface(nullptr, "null.so"), Error);
}

TEST(PlannerPluginLoader, SaysWhatIsWrongWithFilesThatAreNotPlugins) {
  const fs::path text =
      fs::temp_directory_path() / ("pectus_not_a_plugin_" + std::to_string(::getpid()) + ".so");
  std::ofstream(text) << "not a shared library\n";
  auto [kind, message] = Failure([&] { PlannerPlugin::Load(text); });
  EXPECT_EQ(kind, ErrorKind::kBadInput);
  EXPECT_NE(message.find("cannot load the planner plugin"), std::string::npos) << message;
  fs::remove(text);
  // A real shared library without the entry point.
  std::tie(kind, message) = Failure([] { PlannerPlugin::Load("libm.so.6"); });
  EXPECT_NE(message.find("not a pectus planner plugin"), std::string::npos) << message;
  // Nothing where it was told to look: a usage error listing the places.
  std::tie(kind, message) = Failure([] { PlannerPlugin::Find("/nonexistent/libpectus_planner.so"); });
  EXPECT_EQ(kind, ErrorKind::kUsage);
  EXPECT_NE(message.find("/nonexistent/libpectus_planner.so"), std::string::npos) << message;
}

TEST(PlannerPluginLoader, FindsThePluginThroughTheEnvironment) {
  ::setenv("PECTUS_PLANNER_PLUGIN", PECTUS_PLANNER_PLUGIN_PATH, 1);
  const auto candidates = PlannerPluginCandidates();
  ASSERT_FALSE(candidates.empty());
  EXPECT_EQ(candidates.front(), fs::path(PECTUS_PLANNER_PLUGIN_PATH));
  EXPECT_EQ(PlannerPlugin::Find().path(), fs::path(PECTUS_PLANNER_PLUGIN_PATH));
  ::unsetenv("PECTUS_PLANNER_PLUGIN");
}

}  // namespace
}  // namespace pectus::planner
