// pectus planner plugin: the dissertation's finite element dataset (§4.1.2): every patient of a table
// under the 24 load cases, written with FemDatasetWriter (io/fem_dataset_h5.h). One patient at a time
// (RunFemDatasetPart: a one-patient part file, a task of the farm in docs/cluster.md), then the parts
// assembled in table order (AssembleFemDataset); the whole table in one call goes through the same parts,
// so a farm's dataset and the serial one are the same bytes.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>

#include "planner_plugin/plugin/planner_session.h"
#include "shape/core/timings.h"
#include "shape/io/patient_table_io.h"

namespace pectus::planner {

/// What the dataset run did.
struct FemDatasetSummary {
  std::int64_t patients = 0, load_cases = 0, results = 0, surface_nodes = 0;
  /// Wall time, s: "generic_ribcage" (reading the table, building the generic ribcage), "patient_ribcages"
  /// (the fits, meshes, factorisations and skins), "fem" (the solves), "response_basis" (if asked),
  /// "write" (the patients' part files), "assemble" (the dataset from the parts).
  Timings timings_s;
  /// One line: "62 patients x 24 load cases = 1488 results, 4321 surface nodes, 95.3 s".
  std::string BriefReport() const;
};

/// Builds, solves and writes one patient (`row` of a patient table) as a one-patient FE dataset at `part`
/// (committed atomically: a temporary file renamed into place), on `generic` (built with
/// settings.generic), with the patient's exact response basis if `basis_options` is given. The part holds
/// everything the dataset keeps of the patient; AssembleFemDataset joins parts. The patient is built on
/// one OpenMP thread: its FE does not give the same last bits on several (the patients are the
/// parallelism). Throws pectus::Error naming the patient.
FemDatasetSummary RunFemDatasetPart(const GenericRibcage& generic, const PatientTableRow& row,
                                    const std::filesystem::path& part, const PlannerSettings& settings,
                                    const BarResponseBasisOptions* basis_options = nullptr);

/// Builds, solves and writes every patient of `table` (one generic ribcage, one factorisation per
/// patient, DissertationLoadCases()), with each patient's exact response basis if `basis_options` is
/// given: each patient's part (RunFemDatasetPart, the patients on OpenMP's threads) in a folder beside
/// `output`, then the parts assembled in table order (AssembleFemDataset). `progress(done, total)` is
/// called after each patient (one call at a time, from any thread). Nothing
/// appears at `output` unless every patient succeeds. Throws pectus::Error naming the patient at fault.
FemDatasetSummary RunFemDataset(const std::filesystem::path& table, const std::filesystem::path& output,
                                const PlannerSettings& settings,
                                const std::function<void(std::int64_t, std::int64_t)>& progress,
                                const BarResponseBasisOptions* basis_options = nullptr);

}  // namespace pectus::planner
