// FE benchmark of the Nuss planner's engine (issue 7 acceptance): one patient's ribcage, all 24 load
// cases of the dissertation (3 bar positions x 8 forces), timed stage by stage; or, with --all, every
// patient of the table, optionally writing the 1488-result dataset. With --ccx, the peer: CalculiX
// (C3D10) on the identical mesh and load, timed in the same run, with the largest difference. With
// --cartilage-sweep, the force to lift the sternum by its depression for a range of cartilage moduli.
// Prints JSON.
//
//   fem_benchmark [--patient 57] [--all] [--dataset fem_dataset.h5] [--table nuss_ct_parameters.csv]
//                 [--threads N] [--cell-mm 6] [--cartilage-mpa 80] [--ccx /usr/bin/ccx] [--cartilage-sweep]
#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <iostream>
#include <nlohmann/json.hpp>
#include <numeric>
#include <string>
#include <vector>

#include "planner_plugin/fem/calculix_io.h"
#include "planner_plugin/io/fem_dataset_h5.h"
#include "planner_plugin/ribcage/generic_ribcage.h"
#include "planner_plugin/ribcage/patient_ribcage.h"
#include "planner_plugin/ribcage/ribcage_fem.h"
#include "shape/core/error.h"
#include "shape/core/log.h"
#include "shape/io/patient_table_io.h"
#include "tests/support/shared_data.h"

namespace {

using namespace pectus::planner;
using pectus::PatientTableRow;
using pectus::Points3;
using pectus::ReadPatientTable;
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

nlohmann::json RunPatient(const GenericRibcage& generic, const PatientTableRow& row,
                          const RibcageFemOptions& options, FemDatasetWriter* dataset) {
  nlohmann::json out;
  out["patient"] = row.patient;
  Stopwatch total, stage;
  const PatientRibcage ribcage = MakePatientRibcage(generic, MeasurementsOf(row));
  out["timings"]["ribcage_fit_and_mesh"] = stage.Lap();
  const RibcageFem fem(ribcage, options);
  out["timings"]["assembly_and_factorisation"] = stage.Lap();
  const std::vector<BarResult> results = fem.Solve(DissertationLoadCases());
  out["timings"]["solve_24_load_cases"] = stage.Lap();
  const std::vector<ForceToLift> lift =
      fem.ForceToLiftSternum({{0.65, false, 1}, {0.75, false, 1}, {0.85, false, 1}});
  out["timings"]["force_to_lift"] = stage.Lap();
  if (dataset != nullptr) {
    dataset->AddPatient(ribcage, results, lift, row.haller_index);
    out["timings"]["dataset_write"] = stage.Lap();
  }
  out["timings"]["total"] = total.Lap();
  const LinearElasticSummary& s = fem.solver().summary();
  out["mesh"] = {{"nodes", s.nodes},
                 {"tets", s.tets},
                 {"free_dofs", s.free_dofs},
                 {"nnz_K_lower", s.factorization.nonzeros_lower},
                 {"nnz_L", s.factorization.nonzeros_factor},
                 {"factorisation_gflop", 1e-9 * s.factorization.flops}};
  out["solver"] = s.BriefReport();
  out["fit"] = ribcage.message;
  out["fit_residual_mm"] =
      ribcage.residual_mm;  // largest |CT - measured| of width, depth, length, depression
  out["measured"] = {{"width_mm", ribcage.measured.width_mm},
                     {"depth_mm", ribcage.measured.depth_mm},
                     {"sternal_length_mm", ribcage.measured.sternal_length_mm},
                     {"depression_mm", ribcage.measured.depression_mm},
                     {"haller_index", ribcage.measured.haller_index},
                     {"ct_haller_index", row.haller_index}};
  for (const ForceToLift& f : lift) {
    const std::string at = std::to_string(f.position.position).substr(0, 4);
    out["force_to_lift_n"][at] = f.force_n;
    out["force_per_20mm_n"][at] = 20.0 / f.lift_per_newton_mm;  // the dissertation's figure: ~1000 N
  }
  out["sternum_lift_mm_at_0.85L_1500N"] = results[23 - 1].sternum_lift_mm;
  return out;
}

// CalculiX on the identical mesh, materials, constraints and one load case (0.85 L, 100 N).
nlohmann::json RunCalculixPeer(const GenericRibcage& generic, const PatientTableRow& row,
                               const RibcageFemOptions& options, const std::string& ccx) {
  const PatientRibcage ribcage = MakePatientRibcage(generic, MeasurementsOf(row));
  Stopwatch ours;
  const RibcageFem fem(ribcage, options);
  const LoadCase load{"bar", fem.NodalForces({0.85, false, 100.0}), {}};
  const Points3 u = fem.solver().Solve({load}).front();
  const nlohmann::json ours_time = ours.Lap();
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / "pectus_fem_benchmark_ccx";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  const RibcageMaterials& m = options.materials;
  WriteCalculixInput(dir / "ribcage.inp", ribcage.mesh, {m.sternum, m.rib, m.cartilage},
                     fem.solver().partition().prescribed, load);
  Stopwatch theirs;
  const std::string command = "cd '" + dir.string() + "' && '" + ccx + "' -i ribcage > ccx.log 2>&1";
  const int status = std::system(command.c_str());
  const nlohmann::json ccx_time = theirs.Lap();  // cpu_s is pectus's only: ccx runs in a child process
  if (status != 0) return {{"error", "ccx failed; see " + (dir / "ccx.log").string()}};
  const Points3 v = ReadCalculixDisplacements(dir / "ribcage.dat", ribcage.mesh.num_nodes());
  std::filesystem::remove_all(dir);
  const double ours_s = ours_time["wall_s"], ccx_s = ccx_time["wall_s"];
  return {{"mesh_nodes", ribcage.mesh.num_nodes()},
          {"pectus_assembly_factorisation_solve", ours_time},
          {"ccx_wall_s", ccx_s},
          {"ccx_over_pectus_wall", ccx_s / ours_s},
          {"max_abs_difference_over_max_abs_u", (u - v).cwiseAbs().maxCoeff() / v.cwiseAbs().maxCoeff()}};
}

// Force to lift the sternum by its depression at 0.65/0.75/0.85 L for cartilage moduli from 5 to 640 MPa.
nlohmann::json CartilageSweep(const GenericRibcage& generic, const PatientTableRow& row) {
  const PatientRibcage ribcage = MakePatientRibcage(generic, MeasurementsOf(row));
  nlohmann::json out = nlohmann::json::array();
  for (double e : {5.0, 10.0, 20.0, 40.0, 80.0, 160.0, 320.0, 640.0}) {
    RibcageFemOptions options;
    options.materials.cartilage.youngs_modulus_mpa = e;
    const RibcageFem fem(ribcage, options);
    nlohmann::json entry = {{"cartilage_mpa", e}};
    for (const ForceToLift& f :
         fem.ForceToLiftSternum({{0.65, false, 1}, {0.75, false, 1}, {0.85, false, 1}})) {
      entry["force_to_lift_n"].push_back(f.force_n);
      entry["force_per_20mm_n"].push_back(20.0 / f.lift_per_newton_mm);
    }
    out.push_back(entry);
  }
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  std::string table;  // default: the CT table of the shared folder
  std::string patient = "57", dataset_path, ccx;
  bool all = false, sweep = false;
  GenericRibcageOptions generic_options;
  RibcageFemOptions fem_options;  // materials: sternum and ribs of Table 1, the calibrated cartilage
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
    } else if (a == "--ccx") {
      ccx = next();
    } else if (a == "--cartilage-sweep") {
      sweep = true;
    } else if (a == "--cell-mm") {
      generic_options.rib_cell_length_mm = std::stod(next());
    } else if (a == "--cartilage-mpa") {
      fem_options.materials.cartilage.youngs_modulus_mpa = std::stod(next());
    } else {
      std::cerr
          << "usage: fem_benchmark [--patient ID | --all] [--dataset OUT.h5] [--table CSV] [--threads N] "
             "[--cell-mm MM] [--cartilage-mpa E] [--ccx CCX] [--cartilage-sweep]\n";
      return 2;
    }
  }
  if (table.empty()) {
    if (!pectus::testing_support::HaveSharedFile("fem_benchmark", pectus::testing_support::kPatientTable))
      return 3;
    table = pectus::testing_support::SharedPath(pectus::testing_support::kPatientTable);
  }
  try {
    nlohmann::json report;
    report["command"] = std::string(argv[0]);
    for (int i = 1; i < argc; ++i) report["command"] = report["command"].get<std::string>() + " " + argv[i];
    report["threads"] = omp_get_max_threads();
    report["cartilage_mpa"] = fem_options.materials.cartilage.youngs_modulus_mpa;
    Stopwatch total;
    const std::vector<PatientTableRow> rows = ReadPatientTable(table);
    const GenericRibcage generic = BuildGenericRibcage(generic_options);
    report["generic_ribcage"] = {
        {"corner_nodes", generic.nodes.rows()}, {"tets", generic.tets.rows()}, {"build", total.Lap()}};
    if (!ccx.empty())
      report["calculix_peer"] = RunCalculixPeer(generic, FindPatient(rows, patient, table), fem_options, ccx);
    if (sweep) report["cartilage_sweep"] = CartilageSweep(generic, FindPatient(rows, patient, table));
    if (!all) {
      report["patients"].push_back(
          RunPatient(generic, FindPatient(rows, patient, table), fem_options, nullptr));
    } else {
      std::unique_ptr<FemDatasetWriter> dataset;
      if (!dataset_path.empty())
        dataset = std::make_unique<FemDatasetWriter>(dataset_path, generic, DissertationLoadCases(),
                                                     fem_options.materials);
      pectus::Progress progress("FE of " + std::to_string(rows.size()) + " patients",
                                static_cast<std::int64_t>(rows.size()));
      for (const PatientTableRow& row : rows) {
        report["patients"].push_back(RunPatient(generic, row, fem_options, dataset.get()));
        progress.Advance();
      }
      // Summary over the patients: time per patient and force to lift at each position.
      nlohmann::json summary;
      std::vector<double> seconds;
      for (const auto& p : report["patients"]) seconds.push_back(p["timings"]["total"]["wall_s"]);
      summary["patient_wall_s_max"] = *std::max_element(seconds.begin(), seconds.end());
      summary["patient_wall_s_mean"] = std::accumulate(seconds.begin(), seconds.end(), 0.0) / seconds.size();
      double worst_fit = 0;
      for (const auto& p : report["patients"])
        worst_fit = std::max(worst_fit, p["fit_residual_mm"].get<double>());
      summary["fit_residual_mm_max"] = worst_fit;
      for (const char* position : {"0.65", "0.75", "0.85"}) {
        std::vector<double> f;
        for (const auto& p : report["patients"]) f.push_back(p["force_to_lift_n"][position]);
        std::sort(f.begin(), f.end());
        summary["force_to_lift_n"][position] = {
            {"min", f.front()},
            {"median", f[f.size() / 2]},
            {"max", f.back()},
            {"mean", std::accumulate(f.begin(), f.end(), 0.0) / f.size()}};
        std::vector<double> g;
        for (const auto& p : report["patients"]) g.push_back(p["force_per_20mm_n"][position]);
        std::sort(g.begin(), g.end());
        summary["force_per_20mm_n"][position] = {
            {"min", g.front()}, {"median", g[g.size() / 2]}, {"max", g.back()}};
      }
      report["summary"] = summary;
      if (dataset) {
        dataset->Commit();
        report["dataset"] = {{"path", dataset_path},
                             {"results", rows.size() * 24},
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
