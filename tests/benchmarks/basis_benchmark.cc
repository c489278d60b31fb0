// Benchmark of the planner's exact response basis (issue 14): per patient, the basis of the points a user
// sees (the bone surface's vertices and the skin through its ties) built on the patient's one
// factorisation, against the direct FE solve of the dissertation's 24 load cases and of random
// (position, force) pairs; its size, rank and build time; the time of one full-surface update (bone
// surface + skin) and of the force for a wanted lift, on one thread. Prints JSON.
//
//   basis_benchmark [--patients 57,1,10,30,45 | all] [--random 1000] [--evaluations 20000] [--table CSV]
//                   [--tolerance-mm 0.003]
#include <omp.h>
#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "planner_plugin/plugin/planner_session.h"
#include "planner_plugin/ribcage/bar_response_basis.h"
#include "planner_plugin/ribcage/build_generic_ribcage.h"
#include "planner_plugin/ribcage/build_skin_surface.h"
#include "planner_plugin/ribcage/patient_ribcage.h"
#include "planner_plugin/ribcage/ribcage_fem.h"
#include "shape/core/error.h"
#include "shape/io/patient_table_io.h"
#include "tests/support/shared_data.h"

namespace {

using namespace pectus::planner;
using Clock = std::chrono::steady_clock;
using pectus::Points3;

double Seconds(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

double CpuSeconds() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return u.ru_utime.tv_sec + u.ru_stime.tv_sec + 1e-6 * (u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

std::string LoadAverage() {
  std::ifstream in("/proc/loadavg");
  std::string line;
  std::getline(in, line);
  return line;
}

nlohmann::json RunPatient(const GenericRibcage& generic, const pectus::PatientTableRow& row, int random,
                          int evaluations, const BarResponseBasisOptions& options) {
  nlohmann::json out;
  const PatientRibcage ribcage = MakePatientRibcage(generic, MeasurementsOf(row));
  out["patient"] = ribcage.patient;
  out["nodes"] = ribcage.mesh.num_nodes();
  auto start = Clock::now();
  const RibcageFem fem(ribcage);
  out["assembly_and_factorisation_s"] = Seconds(start);
  const BoneSurface bone = MakeBoneSurface(ribcage);
  const SkinSurface skin = BuildSkinSurface(ribcage);
  std::vector<NodeTies> points;
  for (std::int32_t node : bone.mesh_nodes) points.push_back({{node, 1.0}});
  points.insert(points.end(), skin.ties.begin(), skin.ties.end());
  const auto nb = static_cast<Eigen::Index>(bone.mesh_nodes.size()), ns = skin.mesh.num_vertices();
  out["bone_surface_vertices"] = nb;
  out["skin_vertices"] = ns;

  // The basis.
  start = Clock::now();
  const double cpu0 = CpuSeconds();
  const BarResponseBasis basis(fem, points, options);
  out["basis"] = {{"build_s", Seconds(start)},
                  {"build_cpu_s", CpuSeconds() - cpu0},
                  {"solve_bar_levels_s", basis.timings_s().Seconds("solve_bar_levels")},
                  {"solve_adjoint_s", basis.timings_s().Seconds("solve_adjoint")},
                  {"compress_s", basis.timings_s().Seconds("compress")},
                  {"pack_s", basis.timings_s().Seconds("pack")},
                  {"contact_nodes", basis.num_contact_nodes()},
                  {"rank", basis.rank()},
                  {"megabytes", static_cast<double>(basis.bytes()) / 1e6},
                  {"truncation_bound_mm_at_2000_n", basis.truncation_bound_mm_per_n() * 2000.0}};

  // Against the direct solve: the 24 load cases and `random` (position, force) pairs.
  std::vector<BarLoad> loads = DissertationLoadCases();
  std::mt19937 rng(1400 + static_cast<unsigned>(row.patient));
  std::uniform_real_distribution<double> position(0.05, 0.95), force(10.0, 2000.0);
  for (int k = 0; k < random; ++k) loads.push_back({position(rng), false, force(rng)});
  start = Clock::now();
  std::vector<BarResult> direct;
  for (std::size_t first = 0; first < loads.size(); first += 64) {
    const std::vector<BarLoad> block(
        loads.begin() + static_cast<std::ptrdiff_t>(first),
        loads.begin() + static_cast<std::ptrdiff_t>(std::min(first + 64, loads.size())));
    std::vector<BarResult> r = fem.Solve(block);
    for (BarResult& b : r) direct.push_back({b.load, std::move(b.displacement), b.sternum_lift_mm});
  }
  out["direct_solves_s"] = Seconds(start);
  BarResponseWorkspace ws = basis.MakeWorkspace();
  Points3 u(nb + ns, 3);
  double worst_24 = 0.0, worst_random = 0.0, worst_lift = 0.0, largest = 0.0;
  for (std::size_t k = 0; k < loads.size(); ++k) {
    if (!basis.Evaluate(basis.LevelZ(loads[k]), loads[k].force_n, &ws, u.data()))
      pectus::ThrowFailure("the basis has no contact for " + loads[k].Name());
    Points3 expected(nb + ns, 3);
    for (Eigen::Index i = 0; i < nb; ++i) expected.row(i) = direct[k].displacement.row(bone.mesh_nodes[i]);
    expected.bottomRows(ns) = skin.Deformed(direct[k].displacement) - skin.mesh.vertices.positions;
    const double e = (u - expected).rowwise().norm().maxCoeff();
    (k < 24 ? worst_24 : worst_random) = std::max(k < 24 ? worst_24 : worst_random, e);
    largest = std::max(largest, expected.rowwise().norm().maxCoeff());
    const double lift = basis.LiftPerNewton(basis.LevelZ(loads[k])) * loads[k].force_n;
    worst_lift = std::max(worst_lift, std::abs(lift - direct[k].sternum_lift_mm));
  }
  out["against_direct"] = {{"max_nodal_difference_24_cases_mm", worst_24},
                           {"max_nodal_difference_random_mm", worst_random},
                           {"random_pairs", random},
                           {"max_sternal_lift_difference_mm", worst_lift},
                           {"largest_displacement_mm", largest}};

  // Timing on one thread: full-surface updates at random levels, and the force for a wanted lift.
  Eigen::setNbThreads(1);
  std::vector<double> levels(static_cast<std::size_t>(evaluations));
  for (double& z : levels) z = basis.LevelZ({position(rng), false, 1.0});
  std::vector<double> per_call;
  for (int rep = 0; rep < 5; ++rep) {
    start = Clock::now();
    for (double z : levels) basis.Evaluate(z, 500.0, &ws, u.data());
    per_call.push_back(Seconds(start) / evaluations);
  }
  std::sort(per_call.begin(), per_call.end());
  double sink = 0.0;
  std::vector<double> per_force;
  for (int rep = 0; rep < 5; ++rep) {
    start = Clock::now();
    for (double z : levels) sink += 20.0 / basis.LiftPerNewton(z);
    per_force.push_back(Seconds(start) / evaluations);
  }
  std::sort(per_force.begin(), per_force.end());
  out["one_thread"] = {{"full_surface_update_ms_median_of_5", 1e3 * per_call[2]},
                       {"full_surface_update_ms_min", 1e3 * per_call[0]},
                       {"rate_khz", 1e-3 / per_call[2]},
                       {"force_for_a_lift_us_median_of_5", 1e6 * per_force[2]},
                       {"evaluations", evaluations},
                       {"checksum", sink}};
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  std::string table, patients = "57,1,10,30,45";
  int random = 1000, evaluations = 20000;
  BarResponseBasisOptions options;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&]() -> std::string {
      if (i + 1 >= argc) throw std::runtime_error(a + " needs a value");
      return argv[++i];
    };
    if (a == "--patients") {
      patients = next();
    } else if (a == "--random") {
      random = std::stoi(next());
    } else if (a == "--evaluations") {
      evaluations = std::stoi(next());
    } else if (a == "--table") {
      table = next();
    } else if (a == "--tolerance-mm") {
      options.tolerance_mm = std::stod(next());
    } else {
      std::cerr << "usage: basis_benchmark [--patients 57,1,10,30,45] [--random 1000] [--evaluations 20000] "
                   "[--table CSV] [--tolerance-mm 0.003]\n";
      return 2;
    }
  }
  try {
    if (table.empty()) table = pectus::testing_support::SharedPath(pectus::testing_support::kPatientTable);
    nlohmann::json report;
    report["benchmark"] = "basis";
    report["command"] = std::string(argv[0]);
    for (int i = 1; i < argc; ++i) report["command"] = report["command"].get<std::string>() + " " + argv[i];
    report["threads_for_the_build"] = omp_get_max_threads();
    report["loadavg_before"] = LoadAverage();
    report["tolerance_mm"] = options.tolerance_mm;
    const std::vector<pectus::PatientTableRow> rows = pectus::ReadPatientTable(table);
    const GenericRibcage generic = BuildGenericRibcage({});
    std::vector<int> ids;
    if (patients == "all") {
      for (const pectus::PatientTableRow& row : rows) ids.push_back(row.patient);
    } else {
      std::stringstream list(patients);
      for (std::string id; std::getline(list, id, ',');) ids.push_back(std::stoi(id));
    }
    const auto all_start = Clock::now();
    for (int id : ids) {
      std::fprintf(stderr, "basis_benchmark: patient %d\n", id);
      report["patients"].push_back(
          RunPatient(generic, pectus::FindPatient(rows, id, table), random, evaluations, options));
    }
    report["all_patients_wall_s"] = Seconds(all_start);
    report["loadavg_after"] = LoadAverage();
    std::cout << report.dump(2) << "\n";
  } catch (const std::exception& e) {
    std::cerr << "basis_benchmark: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
