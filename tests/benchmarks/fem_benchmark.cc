// FE benchmark of the Nuss planner's engine (issue 7 acceptance): one patient's ribcage, all 24 load
// cases of the dissertation (3 bar positions x 8 forces), timed stage by stage; or, with --all, every
// patient of the table, optionally writing the 1488-result dataset. With --ccx, the peer: CalculiX
// (C3D10) on the identical mesh and load, timed in the same run with the same threads as pectus (1 and 2,
// or --ccx-threads), its input, solve and output apart, with the largest difference. With
// --cartilage-sweep, the force to lift the sternum by its depression for a range of cartilage moduli.
// Prints JSON.
//
//   fem_benchmark [--patient 57] [--all] [--dataset fem_dataset.h5] [--table nuss_ct_parameters.csv]
//                 [--threads N] [--cell-mm 6] [--cartilage-mpa 80] [--ccx /usr/bin/ccx] [--ccx-threads 1,2]
//                 [--cartilage-sweep]
#include <omp.h>
#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <numeric>
#include <string>
#include <vector>

#include "planner_plugin/fem/calculix_io.h"
#include "planner_plugin/io/fem_dataset_h5.h"
#include "planner_plugin/ribcage/build_generic_ribcage.h"
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

// The first line of /proc/loadavg: the machine's load while this ran.
std::string LoadAverage() {
  std::ifstream in("/proc/loadavg");
  std::string line;
  std::getline(in, line);
  return line;
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

// One run of ccx on `deck` (.inp without the extension) in `dir`, with `threads` for every part it
// parallelises (OMP_NUM_THREADS, CCX_NPROC_EQUATION_SOLVER, CCX_NPROC_STIFFNESS, CCX_NPROC_RESULTS):
// wall seconds of the whole process (start, input, solve, output), CPU seconds of the child, and ccx's own
// "Total CalculiX Time" line (its wall clock from main, without the process start).
struct CcxRun {
  bool ok = false;
  double wall_s = 0.0, cpu_s = 0.0, ccx_total_s = -1.0;
  std::vector<std::string> threads_used;  // ccx's "Using up to N cpu(s) for ..." lines, once each
};
CcxRun RunCcx(const std::string& ccx, const std::filesystem::path& dir, const std::string& deck,
              int threads) {
  const std::string t = std::to_string(threads);
  const std::string command = "cd '" + dir.string() + "' && OMP_NUM_THREADS=" + t +
                              " CCX_NPROC_EQUATION_SOLVER=" + t + " CCX_NPROC_STIFFNESS=" + t +
                              " CCX_NPROC_RESULTS=" + t + " '" + ccx + "' -i " + deck + " > " + deck +
                              ".log 2>&1";
  rusage before{}, after{};
  getrusage(RUSAGE_CHILDREN, &before);
  const auto t0 = Clock::now();
  CcxRun run;
  run.ok = std::system(command.c_str()) == 0;
  run.wall_s = std::chrono::duration<double>(Clock::now() - t0).count();
  getrusage(RUSAGE_CHILDREN, &after);
  auto sec = [](const timeval& v) {
    return static_cast<double>(v.tv_sec) + 1e-6 * static_cast<double>(v.tv_usec);
  };
  run.cpu_s = sec(after.ru_utime) - sec(before.ru_utime) + sec(after.ru_stime) - sec(before.ru_stime);
  std::ifstream log(dir / (deck + ".log"));
  for (std::string line; std::getline(log, line);) {
    const auto at = line.find("Total CalculiX Time:");
    if (at != std::string::npos) run.ccx_total_s = std::stod(line.substr(at + 20));
    const auto using_at = line.find("Using up to");
    if (using_at != std::string::npos) {
      const std::string used = line.substr(using_at);
      if (std::find(run.threads_used.begin(), run.threads_used.end(), used) == run.threads_used.end())
        run.threads_used.push_back(used);
    }
  }
  return run;
}

nlohmann::json ToJson(const CcxRun& r) {
  return {{"wall_s", r.wall_s},
          {"cpu_s", r.cpu_s},
          {"ccx_total_calculix_time_s", r.ccx_total_s},
          {"ccx_says", r.threads_used}};
}

// A copy of the deck `from` without `text` (which must be there), or without everything from `text` on.
void DeckWithout(const std::filesystem::path& from, const std::filesystem::path& to, const std::string& text,
                 bool to_the_end) {
  std::ifstream in(from);
  std::string deck((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const auto at = deck.find(text);
  if (at == std::string::npos) pectus::ThrowFailure("no " + text + " in the deck", from.string());
  deck.erase(at, to_the_end ? std::string::npos : text.size());
  std::ofstream(to) << deck;
}

// CalculiX on the identical mesh, materials, constraints and one load case (0.85 L, 100 N), against pectus
// (assembly, factorisation and solve) with the same number of threads, for each count in `threads`. ccx
// is a separate program that reads a text deck and prints its results as text, so its time is split by
// running three decks: the full one (*NODE PRINT of U, read back for the comparison), the same without
// the output request ("no output"), and the model alone, without its *STEP ("input": process start,
// reading the nodes, elements, materials and sections; ccx then stops). solve = no output - input
// (the step: its constraints and loads, stiffness, factorisation, solve); output = full - no output.
// (*NO ANALYSIS is no input-only run: ccx 2.20 still builds the stiffness there, and exits with 201.)
nlohmann::json RunCalculixPeer(const GenericRibcage& generic, const PatientTableRow& row,
                               const RibcageFemOptions& options, const std::string& ccx,
                               const std::vector<int>& thread_counts) {
  const PatientRibcage ribcage = MakePatientRibcage(generic, MeasurementsOf(row));
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / "pectus_fem_benchmark_ccx";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  nlohmann::json out = {
      {"mesh_nodes", ribcage.mesh.num_nodes()},
      {"split",
       "three ccx runs per thread count: the full deck (U printed to the .dat), the same without the "
       "output request, and the model alone without its *STEP (process start, nodes, elements, "
       "materials read; ccx stops); input_s = model alone, solve_s = no output - model alone "
       "(constraints, loads, stiffness, factorisation, solve), output_s = full - no output"},
      {"ccx_threads_variables",
       "OMP_NUM_THREADS, CCX_NPROC_EQUATION_SOLVER, CCX_NPROC_STIFFNESS, CCX_NPROC_RESULTS = "
       "the threads pectus uses"}};
  const int threads_before = omp_get_max_threads();
  double worst_difference = 0.0;
  for (const int threads : thread_counts) {
    omp_set_num_threads(threads);
    Stopwatch ours;
    const RibcageFem fem(ribcage, options);
    const LoadCase load{"bar", fem.NodalForces({0.85, false, 100.0}), {}};
    const Points3 u = fem.solver().Solve({load}).front();
    const nlohmann::json ours_time = ours.Lap();
    const RibcageMaterials& m = options.materials;
    WriteCalculixInput(dir / "ribcage.inp", ribcage.mesh, {m.sternum, m.rib, m.cartilage},
                       fem.solver().partition().prescribed, load);
    DeckWithout(dir / "ribcage.inp", dir / "no_output.inp", "*NODE PRINT, NSET=NALL\nU\n", false);
    DeckWithout(dir / "ribcage.inp", dir / "model.inp", "*STEP\n", true);
    const CcxRun full = RunCcx(ccx, dir, "ribcage", threads);
    const CcxRun no_output = RunCcx(ccx, dir, "no_output", threads);
    const CcxRun model = RunCcx(ccx, dir, "model", threads);
    if (!full.ok || !no_output.ok || !model.ok)
      return {{"error", "ccx failed; see the logs in " + dir.string()}};
    const Points3 v = ReadCalculixDisplacements(dir / "ribcage.dat", ribcage.mesh.num_nodes());
    worst_difference = std::max(worst_difference, (u - v).cwiseAbs().maxCoeff() / v.cwiseAbs().maxCoeff());
    const double ours_s = ours_time["wall_s"], ours_cpu_s = ours_time["cpu_s"];
    const double solve_s = no_output.wall_s - model.wall_s, solve_cpu_s = no_output.cpu_s - model.cpu_s;
    out["runs"].push_back({{"threads", threads},
                           {"pectus_assembly_factorisation_solve", ours_time},
                           {"ccx_full", ToJson(full)},
                           {"ccx_no_output", ToJson(no_output)},
                           {"ccx_model_only", ToJson(model)},
                           {"ccx_input_s", model.wall_s},
                           {"ccx_solve_s", solve_s},
                           {"ccx_output_s", full.wall_s - no_output.wall_s},
                           {"ccx_solve_cpu_s", solve_cpu_s},
                           {"ccx_full_over_pectus_wall", full.wall_s / ours_s},
                           {"ccx_solve_over_pectus_wall", solve_s / ours_s},
                           {"ccx_full_over_pectus_cpu", full.cpu_s / ours_cpu_s},
                           {"ccx_solve_over_pectus_cpu", solve_cpu_s / ours_cpu_s}});
  }
  omp_set_num_threads(threads_before);
  std::filesystem::remove_all(dir);
  out["max_abs_difference_over_max_abs_u"] = worst_difference;
  return out;
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
  std::vector<int> ccx_threads = {1, 2};
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
    } else if (a == "--ccx-threads") {
      ccx_threads.clear();
      const std::string list = next();
      for (std::size_t at = 0; at < list.size();) {
        const std::size_t comma = std::min(list.find(',', at), list.size());
        ccx_threads.push_back(std::stoi(list.substr(at, comma - at)));
        at = comma + 1;
      }
    } else if (a == "--cartilage-sweep") {
      sweep = true;
    } else if (a == "--cell-mm") {
      generic_options.rib_cell_length_mm = std::stod(next());
    } else if (a == "--cartilage-mpa") {
      fem_options.materials.cartilage.youngs_modulus_mpa = std::stod(next());
    } else {
      std::cerr
          << "usage: fem_benchmark [--patient ID | --all] [--dataset OUT.h5] [--table CSV] [--threads N] "
             "[--cell-mm MM] [--cartilage-mpa E] [--ccx CCX] [--ccx-threads 1,2] [--cartilage-sweep]\n";
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
    report["loadavg_before"] = LoadAverage();
    report["cartilage_mpa"] = fem_options.materials.cartilage.youngs_modulus_mpa;
    Stopwatch total;
    const std::vector<PatientTableRow> rows = ReadPatientTable(table);
    const GenericRibcage generic = BuildGenericRibcage(generic_options);
    report["generic_ribcage"] = {
        {"corner_nodes", generic.nodes.rows()}, {"tets", generic.tets.rows()}, {"build", total.Lap()}};
    if (!ccx.empty())
      report["calculix_peer"] =
          RunCalculixPeer(generic, FindPatient(rows, patient, table), fem_options, ccx, ccx_threads);
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
    report["loadavg_after"] = LoadAverage();
    std::cout << report.dump(2) << "\n";
  } catch (const pectus::Error& e) {
    std::cerr << "fem_benchmark: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
