// pectus datasets: chests of real Nuss-procedure patients from their CT parameters
// (../shared/datasets/patients/nuss_ct_parameters.csv; dissertation Appendix A, table 3), read by
// pectus::ReadPatientTable (shape/io/patient_table_io.h).
#pragma once

#include <cstdint>

#include "datasets/chest_measurement.h"
#include "datasets/chest_parameters.h"
#include "datasets/chest_population.h"
#include "shape/io/patient_table_io.h"

namespace pectus::datasets {

/// Options for MakePatientChest.
struct PatientFitOptions {
  double tolerance_mm = 1e-3;  ///< stop when width, depth and depression are all this close
  int max_iterations = 40;
  double soft_tissue_scale = 0.8;  ///< soft tissue of a (teenage) patient relative to the adult mean, before
                                   ///< the size ratio
};

/// A patient's chest and how well it reproduces the row.
struct PatientChest {
  ChestParameters parameters;  ///< saucer-type depression, no torsion, at the reference level
  ChestMeasurement wall;       ///< MeasureChest of the chest wall (what the row describes)
  ChestMeasurement skin;       ///< MeasureChest of the skin (for information)
  int iterations = 0;
  double residual_mm = 0.0;  ///< largest |measured - row| of width, depth, depression on the wall
};

/// Builds a chest whose chest wall, measured as CT is (MeasureChest), has the row's width, depth and
/// depression, and whose sternal length is the row's; the skin lies over it with the population's mean
/// soft tissue scaled to the patient's size and subject-specific detail drawn from `seed`. The depression is
/// a centred saucer (the table's patients are all of the broad symmetric type); its depth, W and D are
/// found by fixed-point iteration on the measurement.
PatientChest MakePatientChest(const PatientTableRow& row, std::uint64_t seed,
                              const PopulationModel& population, const PatientFitOptions& options = {});

}  // namespace pectus::datasets
