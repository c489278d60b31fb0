// The planner plugin loaded as any host loads it (dlopen of the built libpectus_planner.so), for the tests of
// its C boundary; and the coarse mesh and skin that keep them quick.
#pragma once

#include <dlfcn.h>
#include <gtest/gtest.h>

#include "planner_plugin/api/planner_api.h"

namespace pectus::testing_support {

class PluginTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    handle_ = dlopen(PECTUS_PLANNER_PLUGIN_PATH, RTLD_NOW | RTLD_LOCAL);
    ASSERT_NE(handle_, nullptr) << dlerror();
    const auto entry = reinterpret_cast<PectusPlannerEntryFn>(dlsym(handle_, PECTUS_PLANNER_ENTRY_POINT));
    ASSERT_NE(entry, nullptr);
    api_ = entry();
  }
  static void TearDownTestSuite() { dlclose(handle_); }
  // Coarse mesh and skin, to keep the tests quick.
  static PectusPlannerOptions Coarse() {
    PectusPlannerOptions o{};
    api_->default_options(&o);
    o.rib_cell_length_mm = 10;
    o.sternum_cells_along = 28;
    o.skin_rows = 24;
    o.skin_columns = 32;
    return o;
  }
  static void* handle_;
  static const PectusPlannerInterface* api_;
};
inline void* PluginTest::handle_ = nullptr;
inline const PectusPlannerInterface* PluginTest::api_ = nullptr;

}  // namespace pectus::testing_support
