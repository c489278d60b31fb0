#include "planner_plugin/plugin/fem_dataset_run.h"

#include <chrono>

#include "planner_plugin/io/fem_dataset_h5.h"
#include "shape/core/error.h"
#include "shape/io/patient_table_io.h"

namespace pectus::planner {

FemDatasetSummary RunFemDataset(const std::filesystem::path& table, const std::filesystem::path& output,
                                const PlannerSettings& settings,
                                const std::function<void(std::int64_t, std::int64_t)>& progress) {
  const auto start = std::chrono::steady_clock::now();
  const std::vector<PatientTableRow> rows = ReadPatientTable(table);
  const GenericRibcage generic = BuildGenericRibcage(settings.generic);
  const std::vector<BarLoad> loads = DissertationLoadCases();
  std::vector<BarLoad> positions;
  for (const BarLoad& load : loads) {
    if (positions.empty() || positions.back().position != load.position)
      positions.push_back({load.position, false, 1.0});
  }
  FemDatasetWriter writer(output, generic, loads, settings.fem.materials);
  const auto total = static_cast<std::int64_t>(rows.size());
  for (std::int64_t i = 0; i < total; ++i) {
    const PatientTableRow& row = rows[static_cast<std::size_t>(i)];
    const PatientRibcage ribcage = MakePatientRibcage(generic, MeasurementsOf(row), settings.patient);
    if (!ribcage.converged && ribcage.residual_mm > 1.0) {
      ThrowFailure("the generated ribcage does not reproduce the CT measurements: " + ribcage.message,
                   table.string());
    }
    const RibcageFem fem(ribcage, settings.fem);
    writer.AddPatient(ribcage, fem.Solve(loads), fem.ForceToLiftSternum(positions), row.haller_index);
    if (progress) progress(i + 1, total);
  }
  writer.Commit();
  FemDatasetSummary summary;
  summary.patients = total;
  summary.load_cases = static_cast<std::int64_t>(loads.size());
  summary.results = total * summary.load_cases;
  summary.surface_nodes = writer.num_surface_nodes();
  summary.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return summary;
}

}  // namespace pectus::planner
