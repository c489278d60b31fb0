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
                                const std::function<void(std::int64_t, std::int64_t)>& progress,
                                const BarResponseBasisOptions* basis_options) {
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
    std::optional<PlannerSession> session;
    {
      auto t = summary.timings_s.Time("patient_ribcages");
      session.emplace(generic, MeasurementsOf(row), settings);  // refuses a fit that misses the CT
    }
    std::vector<BarResult> results;
    std::vector<ForceToLift> lift;
    {
      auto t = summary.timings_s.Time("fem");
      results = session->fem().Solve(loads);
      lift = session->fem().ForceToLiftSternum(positions);
    }
    std::optional<StoredResponseBasis> basis;
    if (basis_options != nullptr) {
      auto t = summary.timings_s.Time("response_basis");
      session->BuildBasis(*basis_options);
      basis = session->StoreBasis();
    }
    {
      auto t = summary.timings_s.Time("write");
      writer->AddPatient(session->ribcage(), results, lift, row.haller_index, basis ? &*basis : nullptr);
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
