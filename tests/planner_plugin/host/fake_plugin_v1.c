/* A planner plugin of interface version 1, as pectus 0.1 built them: its table ends after write_dataset
 * (no basis, no deform call). A host of this interface must refuse it with a clear message
 * (tests/planner_plugin/host/planner_plugin_loader_test.cc). Everything but the version and size is empty. */
#include <stddef.h>

#include "planner_plugin/api/planner_api.h"

static const PectusPlannerInterface kOldInterface = {
    1u, (uint32_t)offsetof(PectusPlannerInterface, build_basis), "an old planner", 0, 0, 0, 0, 0, 0, 0, 0,
    0, 0, 0, 0, 0, 0, 0, 0};

__attribute__((visibility("default"))) const PectusPlannerInterface* pectus_planner_interface(void) {
  return &kOldInterface;
}
