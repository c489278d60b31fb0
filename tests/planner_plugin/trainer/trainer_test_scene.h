// Shared by the trainer's tests: patients' scenes built once per test program, on a coarse ribcage mesh
// (8 mm rib cells) that keeps the sanitizer run short.
#pragma once

#include <map>
#include <memory>

#include "planner_plugin/ribcage/build_generic_ribcage.h"
#include "planner_plugin/ribcage/patient_ribcage.h"
#include "planner_plugin/trainer/trainer_scene.h"
#include "shape/io/patient_table_io.h"
#include "tests/support/shared_data.h"

namespace pectus::trainer::testing {

inline const planner::GenericRibcage& CoarseGenericRibcage() {
  static const planner::GenericRibcage generic = [] {
    planner::GenericRibcageOptions o;
    o.sternum_cells_along = 28;
    o.rib_cell_length_mm = 8.0;
    return planner::BuildGenericRibcage(o);
  }();
  return generic;
}

/// Patient `number`'s fitted ribcage (the shared CT table), made once.
inline const planner::PatientRibcage& RibcageOf(int number) {
  static std::map<int, std::unique_ptr<planner::PatientRibcage>> cache;
  auto& slot = cache[number];
  if (!slot) {
    const std::string table = testing_support::SharedPath(testing_support::kPatientTable);
    const auto rows = ReadPatientTable(table);
    slot = std::make_unique<planner::PatientRibcage>(planner::MakePatientRibcage(
        CoarseGenericRibcage(), planner::MeasurementsOf(FindPatient(rows, number, table))));
  }
  return *slot;
}

/// Patient `number`'s trainer scene with the default options but organs of 3 subdivisions (1280
/// triangles: faster under the sanitizers), made once.
inline const TrainerScene& SceneOf(int number) {
  static std::map<int, std::unique_ptr<TrainerScene>> cache;
  auto& slot = cache[number];
  if (!slot) {
    TrainerSceneOptions options;
    options.organ_subdivisions = 3;
    slot = std::make_unique<TrainerScene>(BuildTrainerScene(RibcageOf(number), options));
  }
  return *slot;
}

}  // namespace pectus::trainer::testing
