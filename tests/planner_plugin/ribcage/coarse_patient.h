// Test helper: patient 57 of the shared CT table on a coarser mesh than the default (10 mm cells), its
// ribcage and its factorised FE model, built once per test suite (the fixtures of the ribcage's FE tests).
#pragma once

#include <gtest/gtest.h>

#include <string>

#include "planner_plugin/ribcage/build_generic_ribcage.h"
#include "planner_plugin/ribcage/patient_ribcage.h"
#include "planner_plugin/ribcage/ribcage_fem.h"
#include "shape/io/patient_table_io.h"
#include "tests/support/require_shared_data.h"

namespace pectus::planner::testing {

/// A fixture whose suite shares patient 57's coarse ribcage and FE model (skipped without the shared
/// patient table). Derive, then `using CoarsePatient57Test::fem_` etc. in the tests.
class CoarsePatient57Test : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    if (!testing_support::MissingSharedFile(testing_support::kPatientTable).empty()) return;  // see SetUp
    GenericRibcageOptions o;
    o.sternum_cells_along = 28;
    o.rib_cell_length_mm = 10.0;
    generic_ = new GenericRibcage(BuildGenericRibcage(o));
    const std::string table = testing_support::SharedPath(testing_support::kPatientTable);
    const auto rows = ReadPatientTable(table);
    patient_ =
        new PatientRibcage(MakePatientRibcage(*generic_, MeasurementsOf(FindPatient(rows, 57, table))));
    fem_ = new RibcageFem(*patient_);
  }
  void SetUp() override { PECTUS_REQUIRE_SHARED_FILE(testing_support::kPatientTable); }
  static void TearDownTestSuite() {
    delete fem_;
    delete patient_;
    delete generic_;
    fem_ = nullptr, patient_ = nullptr, generic_ = nullptr;
  }
  static inline GenericRibcage* generic_ = nullptr;
  static inline PatientRibcage* patient_ = nullptr;
  static inline RibcageFem* fem_ = nullptr;
};

}  // namespace pectus::planner::testing
