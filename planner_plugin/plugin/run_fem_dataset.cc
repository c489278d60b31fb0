#include "planner_plugin/plugin/run_fem_dataset.h"

#include <cstdio>
#include <optional>
#include <vector>

#include "planner_plugin/io/fem_dataset_h5.h"
#include "shape/core/error.h"
#include "shape/io/patient_table_io.h"

namespace pectus::planner {

FemDatasetSummary RunFemDataset(const std::filesystem::path& table, const std::filesystem::path& output,
                                const PlannerSettings& settings,
                                const std::function<void(std::int64_t, std::int64_t)>& progress) {
  FemDatasetSummary summary;
  std::vector<PatientTableRow> rows;
  GenericRibcage generic;
  {
    auto t = summary.timings_s.Time("generic_ribcage");
    rows = ReadPatientTable(table);
    generic = BuildGenericRibcage(settings.generic);
  }
  const std::vector<BarLoad> loads = DissertationLoadCases();
  std::vector<BarLoad> positions;
  for (const BarLoad& load : loads) {
    if (positions.empty() || positions.back().position != load.position)
      positions.push_back({load.position, false, 1.0});
  }
  std::optional<FemDatasetWriter> writer;
  {
    auto t = summary.timings_s.Time("write");
    writer.emplace(output, generic, loads, settings.fem.materials);
  }
  const auto total = static_cast<std::int64_t>(rows.size());
  for (std::int64_t i = 0; i < total; ++i) {
    const PatientTableRow& row = rows[static_cast<std::size_t>(i)];
    PatientRibcage ribcage;
    {
      auto t = summary.timings_s.Time("patient_ribcages");
      ribcage = MakePatientRibcage(generic, MeasurementsOf(row), settings.patient);
    }
    if (!ribcage.converged && ribcage.residual_mm > 1.0) {
      ThrowFailure("the generated ribcage does not reproduce the CT measurements: " + ribcage.message,
                   table.string());
    }
    std::vector<BarResult> results;
    std::vector<ForceToLift> lift;
    {
      auto t = summary.timings_s.Time("fem");
      const RibcageFem fem(ribcage, settings.fem);
      results = fem.Solve(loads);
      lift = fem.ForceToLiftSternum(positions);
    }
    {
      auto t = summary.timings_s.Time("write");
      writer->AddPatient(ribcage, results, lift, row.haller_index);
    }
    if (progress) progress(i + 1, total);
  }
  {
    auto t = summary.timings_s.Time("write");
    writer->Commit();
  }
  summary.patients = total;
  summary.load_cases = static_cast<std::int64_t>(loads.size());
  summary.results = total * summary.load_cases;
  summary.surface_nodes = writer->num_surface_nodes();
  return summary;
}

std::string FemDatasetSummary::BriefReport() const {
  char line[200];
  std::snprintf(line, sizeof(line),
                "%lld patients x %lld load cases = %lld results, %lld surface nodes, %.1f s",
                static_cast<long long>(patients), static_cast<long long>(load_cases),
                static_cast<long long>(results), static_cast<long long>(surface_nodes), timings_s.Total());
  return line;
}

}  // namespace pectus::planner
