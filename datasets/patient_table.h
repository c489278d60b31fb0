// pectus datasets: chests of real Nuss-procedure patients from their CT parameters
// (../shared/datasets/patients/nuss_ct_parameters.csv; dissertation Appendix A, table 3).
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "datasets/chest_measurement.h"
#include "datasets/chest_parameters.h"
#include "datasets/chest_population.h"

namespace pectus::datasets {

/// One row of the patient table (CT measurements of the ribcage, mm).
struct PatientRow {
  int patient = 0;                 ///< patient number (1-62)
  double haller_index = 0.0;       ///< transverse inner width / sternum-to-spine distance
  double width_mm = 0.0;           ///< ribcage width on the slice of deepest depression
  double sternal_length_mm = 0.0;  ///< sternal length
  double depth_mm = 0.0;           ///< ribcage depth on the same slice
  double depression_mm = 0.0;      ///< from the highest point of the ribcage to the sternum
  int line = 0;                    ///< 1-based line in the file
};

/// Reads the table: a header `patient,haller_index,width_mm,sternal_length_mm,depth_mm,depression_mm`
/// (columns in any order, others ignored) and one row per patient. Throws Error(kBadInput) naming the file
/// and line for a missing column, a malformed number or a duplicate patient.
std::vector<PatientRow> ReadPatientTable(const std::filesystem::path& path);

/// The row of patient `number`; throws Error(kBadInput) naming `table` if there is none.
const PatientRow& FindPatient(const std::vector<PatientRow>& rows, int number, const std::string& table);

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
PatientChest MakePatientChest(const PatientRow& row, std::uint64_t seed, const PopulationModel& population,
                              const PatientFitOptions& options = {});

}  // namespace pectus::datasets
