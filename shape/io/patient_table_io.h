// pectus: the table of CT measurements of Nuss-procedure patients (CSV), e.g.
// ../shared/datasets/patients/nuss_ct_parameters.csv (dissertation Appendix A, Table 3; columns in its
// SOURCE.md). One reader for every user: the generator of patient chests (datasets/) and the planner's
// patient ribcages (planner_plugin/). On pectus::core only (its own target, pectus::patient_table_io), so
// the planner plugin reads it without the rest of shape/io.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

namespace pectus {

/// One row of the patient table: CT measurements of the ribcage on the slice of deepest depression.
struct PatientTableRow {
  int patient = 0;                 ///< patient number (column `patient`), a positive whole number
  double haller_index = 0.0;       ///< inner width / sternum-to-spine distance (0 when the column is absent)
  double width_mm = 0.0;           ///< ribcage width, 100-500 (image mm: divide by the magnification)
  double sternal_length_mm = 0.0;  ///< sternal length, 40-400
  double depth_mm = 0.0;           ///< ribcage depth, 60-400, not more than the width
  double depression_mm = 0.0;  ///< highest point of the ribcage to the sternum, 0-60, under half the depth
  double magnification = 1.0;  ///< CT magnification, 0.2-5 (column optional: 1)
  double torsion_deg = 0.0;    ///< sternal torsion, -45 to 45 (column optional: 0)
  std::int64_t line = 0;       ///< 1-based line of the row in its file
};

/// Parses a patient table held in memory; `name` is the file named in errors. The first non-blank line
/// is the header naming the columns, in any order: `patient`, `width_mm`, `sternal_length_mm`,
/// `depth_mm`, `depression_mm` (required), `haller_index`, `magnification`, `torsion_deg` (optional);
/// other columns are ignored. Lines starting with '#' and blank lines are skipped; cells may be quoted.
/// Throws Error(kBadInput) naming the file, the line and the column for: a missing column, a missing or
/// malformed value, a value out of its range (above), a duplicate patient, or a table without rows.
std::vector<PatientTableRow> ParsePatientTable(std::string_view text, const std::string& name);

/// Reads a patient table file (as ParsePatientTable); Error(kBadInput) if it cannot be read.
std::vector<PatientTableRow> ReadPatientTable(const std::filesystem::path& path);

/// The row of patient `number`. Throws Error(kUsage) naming `table` and the patients it has if there is
/// none.
const PatientTableRow& FindPatient(const std::vector<PatientTableRow>& rows, int number,
                                   const std::string& table);

/// The row of patient `id` given as text (e.g. a command-line value "57"); Error(kUsage) if `id` is not a
/// patient number or the table has no such patient.
const PatientTableRow& FindPatient(const std::vector<PatientTableRow>& rows, std::string_view id,
                                   const std::string& table);

}  // namespace pectus
