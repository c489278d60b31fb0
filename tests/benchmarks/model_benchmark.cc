// Benchmarks and acceptance measurements of the shape model (issue 6), printed as JSON; figures and
// commands in docs/benchmarks/model.md.
//   model_benchmark pca [SUBJECTS=1000]          PCA time (Gram route) against Eigen's SVD and numpy's SVD
//                                                and Gram route, as ratios
//   model_benchmark impute [SUBJECTS=2000]       the imputation of unseen vertices: time and fill error
//   model_benchmark model [SUBJECTS=2000]        the pipeline's model step (imputation, PCA) as collectives:
//                                                under mpirun shared among the ranks; times, and a digest
//                                                of the result, the same for any number of ranks
//   model_benchmark holefill COHORT OUT [PNG]    hole filling and the profile-fit choice, on the surfaces
//                                                that `pectus pipeline COHORT --out OUT` made
//   model_benchmark cohort COHORT OUT            the pipeline's mean and modes against the generator's truth
//                                                and a Monte Carlo population of M (--population M, --pool P)
//   model_benchmark population COHORT OUT FILE [--work DIR]
//                                                only the Monte Carlo reference of `cohort`, its model's
//                                                doubles to FILE; under mpirun on the task farm (one rank
//                                                per core), the same bytes for any number of ranks
//   model_benchmark all [WORK=/tmp/pectus_model_benchmark] [PECTUS=the pectus beside this build]
//                                                every acceptance figure of issue 6 in one run: synth cohorts
//                                                of 11 (seed 7) and 30 (seed 11), `pectus pipeline` on each
//                                                (wall and CPU time), hole filling, truth, PCA of 1000
#ifndef PECTUS_HAVE_DATASETS
#include <cstdio>
int main() {
  std::fprintf(stderr, "model_benchmark needs the virtual scanner: configure with the datasets component\n");
  return 2;
}
#else
#include <omp.h>
#include <sys/resource.h>

#include <Eigen/Eigenvalues>
#include <Eigen/SVD>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <optional>
#include <random>
#include <stdexcept>
#include <thread>
#include <vector>

#ifdef PECTUS_HAVE_MPI
#include "apps/mpi_task_runner.h"
#endif
#include "model_benchmark_holefill.h"
#include "model_benchmark_truth.h"
#include "shape/io/landmark_io.h"
#include "shape/io/mesh_io.h"
#include "shape/model/hole_fill_validation.h"
#include "shape/model/impute_missing_vertices.h"
#include "shape/model/model_figures.h"
#include "shape/model/shape_model.h"

namespace pectus::bench {
namespace {

namespace fs = std::filesystem;

// The imputation of unseen vertices (shape/model/impute_missing_vertices.h) on N subjects of the
// generator's population on the 51 x 101 grid: 60 % of them with a hole (a disk of 4 to 12 grid cells'
// radius, at a random place), started 5 mm off the truth there; the time of ImputeMissingVertices with the
// pipeline's options (a model of the first 256 others, the core iterated, the rest filled once), and the
// fills against the truth.
struct HoledCohort {
  Eigen::MatrixXd truth, start;
  Eigen::Matrix<bool, Eigen::Dynamic, Eigen::Dynamic> seen;
  int holed = 0;
};
HoledCohort MakeHoledCohort(int n) {
  const datasets::PopulationModel population = datasets::PopulationModel::Default();
  const datasets::ShapeGrid grid;
  Eigen::MatrixXd truth(n, 3 * grid.size());
#pragma omp parallel for schedule(dynamic)
  for (int i = 0; i < n; ++i) {
    const datasets::ChestSurface s(datasets::SampleSubject(population, 1000 + i).parameters);
    truth.row(i) = ToShapeVector(datasets::SampleGrid(s, grid)).transpose();
  }
  Eigen::Matrix<bool, Eigen::Dynamic, Eigen::Dynamic> seen =
      Eigen::Matrix<bool, Eigen::Dynamic, Eigen::Dynamic>::Constant(n, grid.size(), true);
  Eigen::MatrixXd start = truth;
  std::mt19937_64 rng(17);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  int holed = 0;
  for (int i = 0; i < n; ++i) {
    if (i % 5 >= 3) continue;
    ++holed;
    const double cu = u(rng) * (grid.nu - 1), cv = u(rng) * (grid.nv - 1), r = 4.0 + 8.0 * u(rng);
    for (int a = 0; a < grid.nu; ++a)
      for (int b = 0; b < grid.nv; ++b)
        if (std::hypot(a - cu, b - cv) <= r) {
          const int v = b * grid.nu + a;
          seen(i, v) = false;
          start(i, 3 * v + 2) += 5.0;
        }
  }
  return {std::move(truth), std::move(start), std::move(seen), holed};
}

nlohmann::json Impute(int n) {
  const datasets::ShapeGrid grid;
  const HoledCohort cohort = MakeHoledCohort(n);
  const Eigen::MatrixXd& truth = cohort.truth;
  const Eigen::MatrixXd& start = cohort.start;
  const auto& seen = cohort.seen;
  const int holed = cohort.holed;
  // Without the local correction first (its share of the time), then as the pipeline runs it.
  ImputationOptions options = PipelineOptions().imputation;
  options.local_scale_mm = 0.0;
  double t = Now(), cpu0 = CpuSeconds();
  ImputeMissingVertices(start, seen, options, "population");
  const double without_local = Now() - t, without_local_cpu = CpuSeconds() - cpu0;
  t = Now(), cpu0 = CpuSeconds();
  const ImputationResult r = ImputeMissingVertices(start, seen, PipelineOptions().imputation, "population");
  const double wall = Now() - t, cpu = CpuSeconds() - cpu0;
  double sum = 0.0, worst = 0.0;
  int count = 0;
  for (int i = 0; i < n; ++i)
    for (int v = 0; v < grid.size(); ++v)
      if (!seen(i, v)) {
        const double d = (r.shapes.row(i).segment<3>(3 * v) - truth.row(i).segment<3>(3 * v)).norm();
        sum += d * d, worst = std::max(worst, d), ++count;
      }
  return {{"subjects", n},
          {"holed_subjects", holed},
          {"unseen_vertices", count},
          {"threads", omp_get_max_threads()},
          {"seconds", wall},
          {"cpu_seconds", cpu},
          {"without_local_correction", {{"seconds", without_local}, {"cpu_seconds", without_local_cpu}}},
          {"iterations", r.iterations},
          {"converged", r.converged},
          {"message", r.message},
          {"fill_to_truth_rms_mm", std::sqrt(sum / std::max(1, count))},
          {"fill_to_truth_max_mm", worst}};
}

// The pipeline's model step on N subjects (the `impute` cohort): the imputation, then the PCA, as
// collectives on the runner (under mpirun, every rank; BuildModel in cohort_pipeline.cc); each step's
// wall time on the leader, the leader's eigen decomposition alone (LAPACK's, as the PCA does it, and
// Eigen's SelfAdjointEigenSolver on the same matrix, for the ratio), and a digest of the result's bytes
// (filled shapes, mean, basis, variances, scores), the same for any number of ranks.
nlohmann::json ModelSteps(int n, TaskRunner& runner) {
  const HoledCohort cohort = MakeHoledCohort(n);
  double t = Now();
  const ImputationResult filled =
      ImputeMissingVertices(cohort.start, cohort.seen, PipelineOptions().imputation, "population", &runner);
  const double impute_s = Now() - t;
  t = Now();
  const ShapeModel model = BuildShapeModel(filled.shapes, ShapeModelOptions(), "population", &runner);
  const double pca_s = Now() - t;
  if (!runner.IsLeader()) return {};
  // The leader's part alone: the eigen decomposition of the Gram matrix.
  const Eigen::MatrixXd X = filled.shapes.rowwise() - model.mean.transpose();
  Eigen::MatrixXd G = Eigen::MatrixXd::Zero(n, n);
  G.selfadjointView<Eigen::Lower>().rankUpdate(X);
  t = Now();
  Eigen::VectorXd values;
  Eigen::MatrixXd vectors;
  if (!SymmetricEigen(G, &values, &vectors)) throw std::runtime_error("dsyevd failed");
  const double eig_s = Now() - t;
  t = Now();
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(G);  // Eigen's, for the ratio
  const double eigen_s = Now() - t;
  std::uint64_t digest = 1469598103934665603ull;  // FNV-1a of every double
  auto add = [&](const double* p, Eigen::Index count) {
    const auto* b = reinterpret_cast<const unsigned char*>(p);
    for (Eigen::Index k = 0; k < count * 8; ++k) digest = (digest ^ b[k]) * 1099511628211ull;
  };
  add(filled.shapes.data(), filled.shapes.size());
  add(model.mean.data(), model.mean.size());
  add(model.basis.data(), model.basis.size());
  add(model.variances.data(), model.variances.size());
  add(model.scores.data(), model.scores.size());
  char hex[17];
  std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(digest));
  return {{"subjects", n},
          {"processes", runner.Processes()},
          {"threads", omp_get_max_threads()},
          {"impute_seconds", impute_s},
          {"imputation", filled.message},
          {"pca_seconds", pca_s},
          {"modes", model.num_modes()},
          {"leader_eigen_decomposition_seconds", eig_s},
          {"eigen_decomposition_of", values.size()},
          {"eigen_selfadjoint_solver_seconds", eigen_s},
          {"eigenvalues_largest_difference", (values - eig.eigenvalues()).cwiseAbs().maxCoeff()},
          {"digest", hex}};
}

// 1. PCA of N subjects of the generator's population sampled on a 51 x 101 grid (15453 numbers each), by
// every route in the same run from the same uncentred matrix (centring inside every time): pectus's
// BuildShapeModel (the Gram route: eigen decomposition of X X', modes and scores), Eigen's BDCSVD of X,
// and numpy's full SVD and Gram route (scripts/peers/numpy_pca.py, the same steps as pectus's), each as a
// ratio to pectus's time. numpy is given as many threads as pectus uses (OMP_NUM_THREADS,
// OPENBLAS_NUM_THREADS); the BLAS it runs on is reported.
nlohmann::json Pca(int n) {
  const datasets::PopulationModel population = datasets::PopulationModel::Default();
  const datasets::ShapeGrid grid;
  Eigen::MatrixXd shapes(n, 3 * grid.size());
#pragma omp parallel for schedule(dynamic)
  for (int i = 0; i < n; ++i) {
    const datasets::ChestSurface s(datasets::SampleSubject(population, 1000 + i).parameters);
    shapes.row(i) = ToShapeVector(datasets::SampleGrid(s, grid)).transpose();
  }
  double t = Now();
  const double cpu0 = CpuSeconds();
  const ShapeModel model = BuildShapeModel(shapes);
  const double gram_s = Now() - t, gram_cpu_s = CpuSeconds() - cpu0;
  t = Now();
  const double svd_cpu0 = CpuSeconds();
  const Eigen::MatrixXd X = shapes.rowwise() - shapes.colwise().mean();
  const Eigen::BDCSVD<Eigen::MatrixXd> svd(X, Eigen::ComputeThinV);
  const double svd_s = Now() - t, svd_cpu_s = CpuSeconds() - svd_cpu0;
  const Eigen::VectorXd lambda = svd.singularValues().array().square() / double(n - 1);
  const int k = std::min<int>(20, model.num_modes());
  const double rel =
      ((model.variances.head(k) - lambda.head(k)).array() / lambda.head(k).array()).abs().maxCoeff();
  // numpy on the same (uncentred) matrix, in the same run.
  const int threads = omp_get_max_threads();
  const fs::path raw = fs::temp_directory_path() / "pectus_model_benchmark_shapes.f64";
  std::ofstream(raw, std::ios::binary)
      .write(reinterpret_cast<const char*>(shapes.data()), static_cast<std::streamsize>(shapes.size() * 8));
  const std::string py = "OMP_NUM_THREADS=" + std::to_string(threads) +
                         " OPENBLAS_NUM_THREADS=" + std::to_string(threads) + " /usr/bin/python3 " +
                         PECTUS_SOURCE_DIR + "/scripts/peers/numpy_pca.py " + raw.string() + " " +
                         std::to_string(n) + " " + std::to_string(shapes.cols());
  std::string text;
  if (FILE* p = popen(py.c_str(), "r")) {
    char buf[4096];
    for (std::size_t got; (got = std::fread(buf, 1, sizeof buf, p)) > 0;) text.append(buf, got);
    pclose(p);
  }
  fs::remove(raw);
  nlohmann::json numpy = nlohmann::json::parse(text, nullptr, false);
  nlohmann::json routes = {
      {"pectus_gram",
       {{"what", "pectus BuildShapeModel: eigen of X X', modes, scores"},
        {"seconds", gram_s},
        {"cpu_seconds", gram_cpu_s}}},
      {"eigen_bdcsvd",
       {{"what", "Eigen BDCSVD of X (thin V)"}, {"seconds", svd_s}, {"cpu_seconds", svd_cpu_s}}}};
  if (numpy.is_discarded() || !numpy.contains("routes")) {
    numpy = {{"error", "failed: " + py}};
  } else {
    routes["numpy_svd"] = {{"what", "numpy linalg.svd of X (thin)"},
                           {"seconds", numpy["routes"]["svd"]["seconds_median"]},
                           {"cpu_seconds", numpy["routes"]["svd"]["cpu_seconds_median"]}};
    routes["numpy_gram_eigh"] = {{"what", "numpy linalg.eigh of X X', modes, scores (pectus's steps)"},
                                 {"seconds", numpy["routes"]["gram_eigh"]["seconds_median"]},
                                 {"cpu_seconds", numpy["routes"]["gram_eigh"]["cpu_seconds_median"]}};
    // pectus's variances against numpy's SVD (an independent route).
    const nlohmann::json& v = numpy["routes"]["svd"]["variances_first_20"];
    double numpy_rel = 0.0;
    for (int c = 0; c < k && c < static_cast<int>(v.size()); ++c)
      numpy_rel = std::max(numpy_rel, std::abs(model.variances[c] / v[c].get<double>() - 1.0));
    numpy["max_relative_variance_difference_pectus_vs_numpy_svd_first_20"] = numpy_rel;
    numpy.erase("routes");
  }
  for (auto& [name, r] : routes.items()) {
    r["over_pectus"] = r["seconds"].get<double>() / gram_s;
    r["cpu_over_pectus"] = r["cpu_seconds"].get<double>() / gram_cpu_s;
  }
  return {{"subjects", n},
          {"numbers_per_shape", shapes.cols()},
          {"modes", model.num_modes()},
          {"threads", threads},
          {"pectus_gram_pca_s", gram_s},
          {"pectus_gram_pca_cpu_s", gram_cpu_s},
          {"limit_s", 10},
          {"holds", gram_s <= 10.0},
          {"routes", routes},
          {"numpy", numpy},
          {"max_relative_eigenvalue_difference_first_20", rel}};
}

// Runs a shell command; wall and CPU time (user + system of the children), seconds.
struct Timed {
  int code = -1;
  double wall_s = 0.0, cpu_s = 0.0;
};
Timed Run(const std::string& command) {
  std::cerr << "$ " << command << "\n";
  rusage before{}, after{};
  getrusage(RUSAGE_CHILDREN, &before);
  const double t = Now();
  Timed r;
  r.code = std::system(command.c_str());
  r.wall_s = Now() - t;
  getrusage(RUSAGE_CHILDREN, &after);
  auto sec = [](const timeval& v) { return double(v.tv_sec) + 1e-6 * double(v.tv_usec); };
  r.cpu_s = sec(after.ru_utime) - sec(before.ru_utime) + sec(after.ru_stime) - sec(before.ru_stime);
  if (r.code != 0) throw std::runtime_error("failed (" + std::to_string(r.code) + "): " + command);
  return r;
}

std::string FirstLine(const std::string& path, const std::string& key = "") {
  std::ifstream in(path);
  for (std::string line; std::getline(in, line);) {
    if (key.empty() || line.rfind(key, 0) == 0) return key.empty() ? line : line.substr(line.find(':') + 2);
  }
  return "";
}

// 4. Everything the issue asks for, in one run.
nlohmann::json All(const fs::path& work, const std::string& pectus,
                   const PopulationReferenceOptions& reference) {
  nlohmann::json j;
  j["machine"] = {{"nproc", std::thread::hardware_concurrency()},
                  {"cpu", FirstLine("/proc/cpuinfo", "model name")},
                  {"loadavg_at_start", FirstLine("/proc/loadavg")}};
  fs::remove_all(work);
  fs::create_directories(work);
  const std::string w = work.string();
  // The demo's cohort: 11 subjects, raw sweeps to the HTML report.
  Run(pectus + " synth cohort --subjects 11 --seed 7 --out " + w + "/c11 --quiet");
  const std::string p11 =
      pectus + " pipeline " + w + "/c11 --out " + w + "/o11 --report " + w + "/o11/pipeline.json --quiet";
  const Timed t11 = Run(p11);
  std::ifstream r11(work / "o11/pipeline.json");
  const nlohmann::json report11 = nlohmann::json::parse(r11);
  j["pipeline_11"] = {{"command", p11},
                      {"wall_s", t11.wall_s},
                      {"cpu_s", t11.cpu_s},
                      {"succeeded", report11["succeeded"]},
                      {"report_html", fs::exists(work / "o11/report.html")},
                      {"limit_s", 60},
                      {"holds", t11.wall_s <= 60.0}};
  j["hole_fill"] = HoleFill(work / "c11", work / "o11", report11, work / "hole_fill.png");
  // The acceptance line: the default fill, removed regions up to 30 mm across (a disk and the scan's
  // own holes it touches, model_benchmark_holefill.h), inside and at the border.
  double vs_truth = 0.0, vs_untouched = 0.0, vs_untouched_on_data = 0.0, true_skin = 0.0;
  for (const nlohmann::json& row : j["hole_fill"]) {
    if (row.value("fill", "") != "default" || row["diameter_mm"].get<double>() > 30.0) continue;
    for (const char* place : {"inside", "border"}) {
      vs_truth = std::max(vs_truth, row[place]["holed_vs_truth"]["max_mm"].get<double>());
      vs_untouched = std::max(vs_untouched, row[place]["holed_vs_untouched"]["max_mm"].get<double>());
      true_skin = std::max(true_skin, row[place]["true_skin_holed_vs_true_skin"]["max_mm"].get<double>());
      vs_untouched_on_data = std::max(
          vs_untouched_on_data, row[place]["holed_vs_untouched_where_it_has_data"]["max_mm"].get<double>());
    }
  }
  j["hole_fill_up_to_30_mm"] = {{"max_error_vs_truth_mm", vs_truth},
                                {"max_error_true_skin_holed_vs_true_skin_mm", true_skin},
                                {"max_error_vs_untouched_mm", vs_untouched},
                                {"max_error_vs_untouched_where_it_has_data_mm", vs_untouched_on_data},
                                {"limit_mm", 0.5},
                                {"holds", vs_truth <= 0.5}};
  // Disks that join a hole of the scan itself into a region wider than 30 mm, apart (30 mm disks).
  for (const nlohmann::json& row : j["hole_fill"])
    if (row.value("fill", "") == "default" && row["diameter_mm"].get<double>() == 30.0)
      j["hole_fill_30_mm_disks_in_wider_regions"] = row["wider_regions"];
  // The cohort of 30 against the generator's truth.
  Run(pectus + " synth cohort --subjects 30 --seed 11 --out " + w + "/c30 --quiet");
  const std::string p30 =
      pectus + " pipeline " + w + "/c30 --out " + w + "/o30 --report " + w + "/o30/pipeline.json --quiet";
  const Timed t30 = Run(p30);
  std::ifstream r30(work / "o30/pipeline.json");
  j["pipeline_30"] = {{"command", p30}, {"wall_s", t30.wall_s}, {"cpu_s", t30.cpu_s}};
  j["cohort_30"] = CompareWithTruth(work / "c30", work / "o30", nlohmann::json::parse(r30), reference);
  j["pca_1000"] = Pca(1000);
  j["machine"]["loadavg_at_end"] = FirstLine("/proc/loadavg");
  return j;
}

}  // namespace
}  // namespace pectus::bench

int main(int argc, char** argv) {
  using namespace pectus::bench;
  // Under mpirun the population reference's subjects are farmed out (`population`): one thread per rank.
#ifdef PECTUS_HAVE_MPI
  std::optional<pectus::cli::MpiSession> mpi;
  if (pectus::cli::LaunchedByMpi()) {
    mpi.emplace(&argc, &argv);
    omp_set_num_threads(1);
  }
#endif
  try {
    // --population M [--pool P]: the Monte Carlo reference's sizes (model_benchmark_population.h).
    PopulationReferenceOptions reference;
    std::vector<char*> args;
    std::string work;
    for (int i = 0; i < argc; ++i) {
      const std::string a = argv[i];
      if ((a == "--population" || a == "--pool") && i + 1 < argc)
        (a == "--pool" ? reference.pool : reference.subjects) = std::atoi(argv[++i]);
      else if (a == "--work" && i + 1 < argc)
        work = argv[++i];
      else
        args.push_back(argv[i]);
    }
    argc = static_cast<int>(args.size());
    argv = args.data();
    const std::string what = argc > 1 ? argv[1] : "pca";
    nlohmann::json result;
    if (what == "impute") {
      result = Impute(argc > 2 ? std::atoi(argv[2]) : 2000);
    } else if (what == "model") {
      Eigen::setNbThreads(1);  // the bytes must not depend on the thread count (cluster.md)
      pectus::SerialTaskRunner threads;
      pectus::TaskRunner* runner = &threads;
#ifdef PECTUS_HAVE_MPI
      std::optional<pectus::cli::MpiTaskRunner> ranks;
      if (mpi) runner = &ranks.emplace(*mpi);
#endif
      result = ModelSteps(argc > 2 ? std::atoi(argv[2]) : 2000, *runner);
      if (!runner->IsLeader()) return 0;
    } else if (what == "pca") {
      result = Pca(argc > 2 ? std::atoi(argv[2]) : 1000);
    } else if (what == "holefill" && argc >= 4) {
      std::ifstream in(fs::path(argv[3]) / "pipeline.json");
      result = HoleFill(argv[2], argv[3], nlohmann::json::parse(in), argc > 4 ? argv[4] : "");
    } else if (what == "all") {
      const std::string pectus = argc > 3
                                     ? argv[3]
                                     : (fs::canonical("/proc/self/exe").parent_path() / "../../apps/pectus")
                                           .lexically_normal()
                                           .string();
      result = All(argc > 2 ? argv[2] : "/tmp/pectus_model_benchmark", pectus, reference);
    } else if (what == "population" && argc >= 5) {
      Eigen::setNbThreads(1);  // the reference's bytes must not depend on the thread count (cluster.md)
      std::ifstream in(fs::path(argv[3]) / "pipeline.json");
      pectus::SerialTaskRunner threads;
      ChainFarm farm{&threads, work.empty() ? fs::path(argv[4]).string() + ".work" : work};
#ifdef PECTUS_HAVE_MPI
      std::optional<pectus::cli::MpiTaskRunner> ranks;
      if (mpi) farm.runner = &ranks.emplace(*mpi);
#endif
      result = PopulationOnly(argv[2], argv[3], nlohmann::json::parse(in), reference, farm, argv[4]);
      if (!farm.runner->IsLeader()) return 0;
      fs::remove_all(farm.work);
    } else if (what == "cohort" && argc >= 4) {
      std::ifstream in(fs::path(argv[3]) / "pipeline.json");
      result = CompareWithTruth(argv[2], argv[3], nlohmann::json::parse(in), reference);
    } else {
      std::cerr << "usage: model_benchmark pca [N] | impute [N] | model [N] | holefill COHORT OUT [PNG] | "
                   "cohort COHORT OUT | "
                   "population COHORT OUT FILE [--work DIR] | all [WORK] [PECTUS]\n"
                   "  [--population M=2000] [--pool P=1000]: the population reference's subjects, and the\n"
                   "  independent pool from which cohorts of N are drawn for the sampling spread (0: none)\n"
                   "  (OUT is the folder of `pectus pipeline COHORT --out OUT --report OUT/pipeline.json`)\n";
      return 2;
    }
    std::cout << result.dump(2) << std::endl;
  } catch (const std::exception& e) {
    std::cerr << "model_benchmark: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
#endif  // PECTUS_HAVE_DATASETS
