// pectus planner: the table of CT measurements of the dissertation's patients
// (../shared/datasets/patients/nuss_ct_parameters.csv, documented in its SOURCE.md).
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "planner_plugin/ribcage/patient_ribcage.h"

namespace pectus::planner {

/// One row of the patient table.
struct PatientRow {
  PatientMeasurements measurements;  ///< width, depth, sternal length, depression (mm), magnification 1
  double haller_index = 0;           ///< the Haller index measured on the CT (0 if the column is absent)
};

/// Reads a patient table: CSV with a header naming the columns `patient`, `width_mm`,
/// `sternal_length_mm`, `depth_mm`, `depression_mm` (required) and `haller_index`, `magnification`,
/// `torsion_deg` (optional), in any order. Throws Error(kBadInput) naming the file and line for a
/// missing column, a malformed number, a duplicate patient, or a row that fails
/// PatientMeasurements::IsValid.
std::vector<PatientRow> ReadPatientTable(const std::filesystem::path& path);

/// Parses a patient table from memory; `name` is the file named in errors.
std::vector<PatientRow> ParsePatientTable(const std::string& text, const std::string& name);

/// The row of `patient`; throws Error(kUsage) listing the available patients if it is absent.
const PatientRow& FindPatient(const std::vector<PatientRow>& rows, const std::string& patient);

}  // namespace pectus::planner
