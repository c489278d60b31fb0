/* planner_api.h compiled as C99: the interface is plain C. Reports the layout C sees, so that a C++
 * test (plugin/plugin_entry_test.cc) can check that C and C++ agree on every struct. */
#include <stddef.h>

#include "planner_plugin/api/planner_api.h"

/* Sizes and a few offsets of the interface's structs as C lays them out. */
void pectus_planner_api_layout_from_c(size_t* out, int capacity) {
  const size_t values[] = {sizeof(PectusPlannerStatus),
                           sizeof(PectusPlannerPatient),
                           sizeof(PectusPlannerOptions),
                           sizeof(PectusPlannerMeasurements),
                           sizeof(PectusPlannerMesh),
                           sizeof(PectusPlannerLandmark),
                           sizeof(PectusPlannerBar),
                           sizeof(PectusPlannerCaseResult),
                           sizeof(PectusPlannerForceToLift),
                           sizeof(PectusPlannerDatasetSummary),
                           sizeof(PectusPlannerBasisOptions),
                           sizeof(PectusPlannerBasisSummary),
                           offsetof(PectusPlannerInterface, deform),
                           sizeof(PectusPlannerInterface),
                           offsetof(PectusPlannerInterface, write_dataset),
                           offsetof(PectusPlannerPatient, ct_haller_index),
                           offsetof(PectusPlannerOptions, skin_columns),
                           (size_t)PECTUS_PLANNER_INTERFACE_VERSION,
                           sizeof(PectusPlannerEmulatorOptions),
                           sizeof(PectusPlannerEmulatorFigures),
                           sizeof(PectusPlannerEmulatorPatient),
                           sizeof(PectusPlannerEmulatorEvaluation),
                           offsetof(PectusPlannerEmulatorFigures, worst_lift_patient),
                           offsetof(PectusPlannerInterface, evaluate_emulator),
                           offsetof(PectusPlannerInterface, basis_coefficients),
                           sizeof(PectusPlannerDeviceState),
                           sizeof(PectusPlannerDevice),
                           sizeof(PectusPlannerTrainerTick),
                           sizeof(PectusPlannerTunnel),
                           sizeof(PectusPlannerTrainerScore),
                           sizeof(PectusPlannerScopeView),
                           offsetof(PectusPlannerInterface, trainer_scope_view),
                           offsetof(PectusPlannerInterface, assemble_dataset)};
  int i;
  for (i = 0; i < capacity && i < (int)(sizeof(values) / sizeof(values[0])); ++i) out[i] = values[i];
}
