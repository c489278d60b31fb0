// The serve tests' server: patient 57's table on the coarse test mesh (10 mm rib cells, as
// plan_command_test.cc), the plugin built beside the tests, an average chest file, a free port.
#pragma once

#include <filesystem>
#include <string>

#include "apps/serve/planner_server.h"

namespace pectus::serve::testing {

inline PlannerServerOptions TestServerOptions(const std::string& patient_table,
                                              const std::filesystem::path& average_model) {
  PlannerServerOptions options;
  options.patient_table = patient_table;
  options.model = average_model;
  options.plugin = PECTUS_PLANNER_PLUGIN_PATH;
  options.port = 0;
  options.cell_mm = 10;
  return options;
}

}  // namespace pectus::serve::testing
