/* A planner plugin that implements interface version 2: a host built for version 1 must refuse it
 * (tests/planner_plugin/host/planner_plugin_loader_test.cc). Everything but the version is empty. */
#include "planner_plugin/api/planner_api.h"

static const PectusPlannerInterface kFutureInterface = {
    2u, sizeof(PectusPlannerInterface), "a future planner", 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0};

__attribute__((visibility("default"))) const PectusPlannerInterface* pectus_planner_interface(void) {
  return &kFutureInterface;
}
