// FE benchmark of the Nuss planner's engine (issue 7 acceptance): one patient's ribcage, all 24 load
// cases of the dissertation (3 bar positions x 8 forces), timed stage by stage; or, with --all, every
// patient of the table, optionally writing the 1488-result dataset. Prints JSON.
//
//   fem_benchmark [--patient 57] [--all] [--dataset fem_dataset.h5] [--table nuss_ct_parameters.csv]
//                 [--threads N] [--cell-mm 6]
#include <omp.h>

#include <chrono>
#include <cstdio>
#include <ctime>
#include <iostream>
#include <nlohmann/json.hpp>
#include <string>

#include "planner_plugin/io/fem_dataset_h5.h"
#include "planner_plugin/ribcage/generic_ribcage.h"
#include "planner_plugin/ribcage/patient_ribcage.h"
#include "planner_plugin/ribcage/patient_table.h"
#include "planner_plugin/ribcage/ribcage_fem.h"
#include "shape/core/error.h"
#include "shape/core/log.h"

namespace {

using namespace pectus::planner;
using Clock = std::chrono::steady_clock;

double CpuSeconds() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

// Wall and CPU seconds of one stage.
struct Stopwatch {
  Clock::time_point wall = Clock::now();
  double cpu = CpuSeconds();
  nlohmann::json Lap() {
    const auto now = Clock::now();
    const double c = CpuSeconds();
    nlohmann::json j = {{"wall_s", std::chrono::duration<double>(now - wall).count()}, {"cpu_s", c - cpu}};
    wall = now;
    cpu = c;
    return j;
  }
};

nlohmann::json RunPatient(const GenericRibcage& generic, const PatientRow& row, FemDatasetWriter* dataset) {
  nlohmann::json out;
  out["patient"] = row.measurements.patient;
  Stopwatch total, stage;
  const PatientRibcage ribcage = MakePatientRibcage(generic, row.measurements);
  out["timings"]["ribcage_fit_and_mesh"] = stage.Lap();
  const RibcageFem fem(ribcage);
  out["timings"]["assembly_and_factorisation"] = stage.Lap();
  const std::vector<BarResult> results = fem.Solve(DissertationLoadCases());
  out["timings"]["solve_24_load_cases"] = stage.Lap();
  const std::vector<ForceToLift> lift = fem.ForceToLiftSternum({{0.65, false, 1}, {0.75, false, 1}, {0.85, false, 1}});
  out["timings"]["force_to_lift"] = stage.Lap();
  if (dataset != nullptr) {
    dataset->AddPatient(ribcage, results, lift, row.haller_index);
    out["timings"]["dataset_write"] = stage.Lap();
  }
  out["timings"]["total"] = total.Lap();
  const LinearElasticSummary& s = fem.solver().summary();
  out["mesh"] = {{"nodes", s.nodes}, {"tets", s.tets}, {"free_dofs", s.free_dofs},
                 {"nnz_K_lower", s.factorization.nonzeros_lower}, {"nnz_L", s.factorization.nonzeros_factor},
                 {"factorisation_gflop", 1e-9 * s.factorization.flops}};
  out["solver"] = s.BriefReport();
  out["fit"] = ribcage.message;
  out["measured"] = {{"width_mm", ribcage.measured.width_mm},
                     {"depth_mm", ribcage.measured.depth_mm},
                     {"sternal_length_mm", ribcage.measured.sternal_length_mm},
                     {"depression_mm", ribcage.measured.depression_mm},
                     {"haller_index", ribcage.measured.haller_index},
                     {"ct_haller_index", row.haller_index}};
  for (const ForceToLift& f : lift) {
    out["force_to_lift_n"][std::to_string(f.position.position).substr(0, 4)] = f.force_n;
  }
  out["sternum_lift_mm_at_0.85L_1500N"] = results[23 - 1].sternum_lift_mm;
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  std::string table = std::string(PECTUS_SHARED_DIR) + "/datasets/patients/nuss_ct_parameters.csv";
  std::string patient = "57", dataset_path;
  bool all = false;
  GenericRibcageOptions generic_options;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&]() -> std::string {
      if (i + 1 >= argc) {
        std::cerr << "fem_benchmark: " << a << " needs a value\n";
        std::exit(2);
      }
      return argv[++i];
    };
    if (a == "--patient") {
      patient = next();
    } else if (a == "--all") {
      all = true;
    } else if (a == "--dataset") {
      dataset_path = next();
    } else if (a == "--table") {
      table = next();
    } else if (a == "--threads") {
      omp_set_num_threads(std::stoi(next()));
    } else if (a == "--cell-mm") {
      generic_options.rib_cell_length_mm = std::stod(next());
    } else {
      std::cerr << "usage: fem_benchmark [--patient ID | --all] [--dataset OUT.h5] [--table CSV] [--threads N] "
                   "[--cell-mm MM]\n";
      return 2;
    }
  }
  try {
    nlohmann::json report;
    report["command"] = std::string(argv[0]);
    for (int i = 1; i < argc; ++i) report["command"] = report["command"].get<std::string>() + " " + argv[i];
    report["threads"] = omp_get_max_threads();
    Stopwatch total;
    const std::vector<PatientRow> rows = ReadPatientTable(table);
    const GenericRibcage generic = BuildGenericRibcage(generic_options);
    report["generic_ribcage"] = {{"corner_nodes", generic.nodes.rows()}, {"tets", generic.tets.rows()},
                                 {"build", total.Lap()}};
    if (!all) {
      report["patients"].push_back(RunPatient(generic, FindPatient(rows, patient), nullptr));
    } else {
      std::unique_ptr<FemDatasetWriter> dataset;
      if (!dataset_path.empty()) dataset = std::make_unique<FemDatasetWriter>(dataset_path, generic, DissertationLoadCases());
      pectus::Progress progress("FE of " + std::to_string(rows.size()) + " patients", static_cast<std::int64_t>(rows.size()));
      for (const PatientRow& row : rows) {
        report["patients"].push_back(RunPatient(generic, row, dataset.get()));
        progress.Advance();
      }
      if (dataset) {
        dataset->Commit();
        report["dataset"] = {{"path", dataset_path}, {"results", rows.size() * 24},
                             {"surface_nodes_per_patient", dataset->num_surface_nodes()}};
      }
    }
    report["total"] = total.Lap();
    std::cout << report.dump(2) << "\n";
  } catch (const pectus::Error& e) {
    std::cerr << "fem_benchmark: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
