#include "planner_plugin/plugin/run_fem_dataset.h"

#include <omp.h>
#include <unistd.h>

#include <cstdio>
#include <exception>
#include <optional>
#include <utility>
#include <vector>

#include "planner_plugin/io/fem_dataset_h5.h"
#include "shape/core/error.h"

namespace pectus::planner {
namespace {

namespace fs = std::filesystem;

// A folder removed with everything in it when the object goes.
struct ScratchFolder {
  explicit ScratchFolder(fs::path p) : path(std::move(p)) {
    std::error_code ec;
    fs::remove_all(path, ec);
    if (!fs::create_directories(path, ec) || ec)
      ThrowFailure("cannot create the folder: " + ec.message(), path.string());
  }
  ~ScratchFolder() {
    std::error_code ec;
    fs::remove_all(path, ec);
  }
  ScratchFolder(const ScratchFolder&) = delete;
  ScratchFolder& operator=(const ScratchFolder&) = delete;
  fs::path path;
};

// One OpenMP thread for this thread while the object lives. A patient's FE (the assembly and CHOLMOD's
// factorisation) does not give the same last bits on two threads as on one, nor twice on two threads; a
// dataset's bytes must not depend on where its patients ran, so each is built on one thread (and the
// patients are the parallelism: RunFemDataset, the task farm). CHOLMOD asks for its own team of 4 in the
// supernodal factorisation, whatever omp_set_num_threads says: at the top level, no parallel region may
// be active, which keeps it on this thread too (a coarse patient took 1.5 s instead of 0.8 s, waking 3
// threads per supernode). Inside a parallel region (the patients on threads) nested ones are inactive.
class OneThread {
 public:
  OneThread() : threads_(omp_get_max_threads()), top_level_(!omp_in_parallel()) {
    omp_set_num_threads(1);
    if (top_level_) {
      levels_ = omp_get_max_active_levels();
      omp_set_max_active_levels(0);
    }
  }
  ~OneThread() {
    omp_set_num_threads(threads_);
    if (top_level_) omp_set_max_active_levels(levels_);
  }
  OneThread(const OneThread&) = delete;
  OneThread& operator=(const OneThread&) = delete;

 private:
  int threads_;
  bool top_level_;
  int levels_ = 1;
};

}  // namespace

FemDatasetSummary RunFemDatasetPart(const GenericRibcage& generic, const PatientTableRow& row,
                                    const fs::path& part, const PlannerSettings& settings,
                                    const BarResponseBasisOptions* basis_options) {
  const OneThread one_thread;
  FemDatasetSummary summary;
  const std::vector<BarLoad> loads = DissertationLoadCases();
  std::vector<BarLoad> positions;
  for (const BarLoad& load : loads) {
    if (positions.empty() || positions.back().position != load.position)
      positions.push_back({load.position, false, 1.0});
  }
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
    FemDatasetWriter writer(part, generic, loads, settings.fem.materials);
    writer.AddPatient(session->ribcage(), results, lift, row.haller_index, basis ? &*basis : nullptr);
    writer.Commit();
    summary.surface_nodes = writer.num_surface_nodes();
  }
  summary.patients = 1;
  summary.load_cases = static_cast<std::int64_t>(loads.size());
  summary.results = summary.load_cases;
  return summary;
}

FemDatasetSummary RunFemDataset(const fs::path& table, const fs::path& output,
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
  // The parts beside the output (the same file system), removed afterwards.
  const ScratchFolder folder(output.parent_path() /
                             ("." + output.filename().string() + ".parts-" + std::to_string(::getpid())));
  const auto total = static_cast<std::int64_t>(rows.size());
  std::vector<fs::path> parts;
  for (std::int64_t i = 0; i < total; ++i) parts.push_back(folder.path / (std::to_string(i) + ".h5"));
  // The patients in parallel, each on one thread; the first failure in table order is thrown.
  std::vector<FemDatasetSummary> made(rows.size());
  std::vector<std::exception_ptr> errors(rows.size());
  std::int64_t done = 0;
#pragma omp parallel for schedule(dynamic, 1)
  for (std::int64_t i = 0; i < total; ++i) {
    const auto k = static_cast<std::size_t>(i);
    try {
      made[k] = RunFemDatasetPart(generic, rows[k], parts[k], settings, basis_options);
    } catch (...) {
      errors[k] = std::current_exception();
    }
#pragma omp critical(pectus_fem_dataset_progress)
    if (progress) progress(++done, total);
  }
  for (const std::exception_ptr& e : errors) {
    if (e) std::rethrow_exception(e);
  }
  for (const FemDatasetSummary& part : made) {
    summary.timings_s.Add(part.timings_s);
    summary.load_cases = part.load_cases;
    summary.surface_nodes = part.surface_nodes;
  }
  {
    auto t = summary.timings_s.Time("assemble");
    AssembleFemDataset(parts, output);
  }
  summary.patients = total;
  summary.results = total * summary.load_cases;
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
