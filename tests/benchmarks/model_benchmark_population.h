// model_benchmark: the generator's population in the model's own space, by Monte Carlo. M subjects of
// datasets::PopulationModel::Default() go through the pipeline's chain (ThroughChain: tessellated, cut to
// the ROI, registered to the cohort's reference subject, resampled on their landmark grid), are aligned to
// their mean by rigid generalized Procrustes as the pipeline aligns its grids, and give the reference mean
// and modes. A second, independent pool gives the sampling spread of an N-subject cohort.
#pragma once

#include <omp.h>

#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <random>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include "datasets/chest_population.h"
#include "datasets/seeding.h"
#include "model_benchmark_chain.h"
#include "shape/core/atomic_file.h"
#include "shape/core/task_runner.h"
#include "shape/model/shape_model.h"

namespace pectus::bench {

/// How the Monte Carlo reference is drawn.
struct PopulationReferenceOptions {
  int subjects = 2000;  ///< M, subjects of the reference population (>= 4)
  int pool = 1000;      ///< independent subjects from which cohorts of N are drawn (0 or < N: none)
  int cohorts = 50;     ///< random cohorts of N drawn from the pool
  int modes = 8;        ///< modes compared (k = 1 .. modes)
  /// Base of the subjects' seeds: subject i is SampleSubject(DeriveSeed(seed, kSubject, i)); the pool
  /// continues at i = subjects. `pectus synth cohort --seed S` draws DeriveSeed(S, kSubject, index), so
  /// the two meet only for S = this seed; the cohort's own seeds are skipped as well.
  std::uint64_t seed = 0x706f70756c617469ull;  // "populati"

  bool IsValid(std::string* why) const {
    if (subjects >= 4 && pool >= 0 && cohorts >= 1 && modes >= 1) return true;
    if (why) *why = "the reference needs >= 4 subjects, a pool >= 0, >= 1 cohort and >= 1 mode";
    return false;
  }
};

/// Grids of the population through the chain: one row per subject (3m numbers, mm, reference frame).
struct ChainGrids {
  Eigen::MatrixXd rows;
  int seeds_skipped = 0;  ///< seeds of the sequence that were a cohort subject's and were left out
  int failed = 0;         ///< subjects the chain threw on (left out)
  double wall_s = 0.0, cpu_s = 0.0;
};

/// Where the population's subjects go through the chain: this process's threads, or a task farm
/// (`model_benchmark population` under mpirun, docs/cluster.md) whose tasks commit each subject's grid to
/// `work` (raw doubles; an empty file for a subject the chain threw on), read back in seed order by the
/// leader, so that the reference is the same bytes whatever the number of ranks.
struct ChainFarm {
  TaskRunner* runner = nullptr;
  std::filesystem::path work;
};

/// `count` subjects, seeds DeriveSeed(base_seed, kSubject, 0, 1, ...) but those in `exclude`, through the
/// chain in parallel; progress on stderr. On a farm, only the leader's rows are filled.
inline ChainGrids PopulationThroughChain(std::uint64_t base_seed, int count,
                                         const std::set<std::uint64_t>& exclude, const IcpTarget& target,
                                         const LandmarkSet& landmarks, const PipelineOptions& options,
                                         const std::string& label, const ChainFarm& farm = {}) {
  std::vector<std::uint64_t> seeds;
  int skipped = 0;
  for (std::uint64_t i = 0; static_cast<int>(seeds.size()) < count; ++i) {
    const std::uint64_t s = datasets::DeriveSeed(base_seed, datasets::SeedStream::kSubject, i);
    if (exclude.count(s))
      ++skipped;
    else
      seeds.push_back(s);
  }
  const datasets::PopulationModel population = datasets::PopulationModel::Default();
  ChainGrids out;
  out.seeds_skipped = skipped;
  const double t0 = Now(), cpu0 = CpuSeconds();
  std::vector<Eigen::VectorXd> grids(seeds.size());
  int done = 0;
  auto through_chain = [&](int i) {
    try {  // nothing may leave an OpenMP region; a subject the chain cannot take is counted and left out
      const datasets::ChestSurface surface(datasets::SampleSubject(population, seeds[i]).parameters);
      grids[i] = ThroughChain(surface, target, landmarks, options);
    } catch (const std::exception& e) {
#pragma omp critical(pectus_population_progress)
      std::cerr << label << ": subject seed " << seeds[i] << " failed: " << e.what() << "\n";
    }
#pragma omp critical(pectus_population_progress)
    if (++done % 100 == 0 || done == count)
      std::cerr << label << ": " << done << " of " << count << " subjects through the chain, " << Now() - t0
                << " s\n";
  };
  if (farm.runner == nullptr) {
#pragma omp parallel for schedule(dynamic)
    for (int i = 0; i < count; ++i) through_chain(i);
  } else {
    const std::filesystem::path folder = farm.work / label;
    auto path = [&](int i) { return folder / (std::to_string(seeds[i]) + ".grid"); };
    std::vector<int> todo;
    for (int i = 0; i < count; ++i)
      if (!std::filesystem::exists(path(i))) todo.push_back(i);  // kept by a killed run
    std::filesystem::create_directories(folder);
    farm.runner->Run(todo, [&](int i) {
      through_chain(i);
      WriteFileAtomically(path(i),
                          std::string_view(reinterpret_cast<const char*>(grids[i].data()),
                                           sizeof(double) * static_cast<std::size_t>(grids[i].size())));
      grids[i].resize(0);
    });
    if (!farm.runner->IsLeader()) return out;
    for (int i = 0; i < count; ++i) {  // in seed order, whoever made them
      std::ifstream in(path(i), std::ios::binary | std::ios::ate);
      const auto bytes = static_cast<std::size_t>(in.tellg());
      if (!in || bytes % sizeof(double) != 0) throw std::runtime_error(path(i).string() + ": not a grid");
      grids[i].resize(static_cast<Eigen::Index>(bytes / sizeof(double)));
      in.seekg(0);
      in.read(reinterpret_cast<char*>(grids[i].data()), static_cast<std::streamsize>(bytes));
    }
  }
  std::erase_if(grids, [](const Eigen::VectorXd& g) { return g.size() == 0; });
  out.failed = count - static_cast<int>(grids.size());
  if (grids.size() < 4) throw std::runtime_error(label + ": fewer than 4 subjects went through the chain");
  out.rows.resize(static_cast<Eigen::Index>(grids.size()), grids[0].size());
  for (std::size_t i = 0; i < grids.size(); ++i)
    out.rows.row(static_cast<Eigen::Index>(i)) = grids[i].transpose();
  out.wall_s = Now() - t0, out.cpu_s = CpuSeconds() - cpu0;
  return out;
}

/// Rows of `shapes` aligned to their mean by rigid generalized Procrustes, `iterations` rounds, as
/// cohort_pipeline.cc aligns the subjects' grids; then all moved by one rigid motion that puts their mean
/// on `frame` (the pipeline's mean), so that modes compare in one frame.
inline void AlignRowsToTheirMean(int iterations, const Eigen::VectorXd& frame, Eigen::MatrixXd* shapes) {
  for (int it = 0; it < iterations; ++it) {
    const Eigen::VectorXd mean = shapes->colwise().mean().transpose();
#pragma omp parallel for schedule(static)
    for (Eigen::Index r = 0; r < shapes->rows(); ++r)
      shapes->row(r) = AlignedTo(mean, shapes->row(r).transpose()).transpose();
  }
  const Similarity3 T_frame_mean = AlignmentTo(frame, shapes->colwise().mean().transpose());
#pragma omp parallel for schedule(static)
  for (Eigen::Index r = 0; r < shapes->rows(); ++r)
    shapes->row(r) = Moved(T_frame_mean, shapes->row(r).transpose()).transpose();
}

/// Largest principal angle (deg) between the first k modes of a and b, k = 1 .. modes.
inline std::vector<double> AnglesForEachK(const ShapeModel& a, const ShapeModel& b, int modes) {
  std::vector<double> out;
  for (int k = 1; k <= std::min({modes, a.num_modes(), b.num_modes()}); ++k)
    out.push_back(PrincipalAnglesDeg(a.basis, b.basis, k).maxCoeff());
  return out;
}

inline double Quantile(std::vector<double> v, double q) {
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, static_cast<std::size_t>(q * double(v.size())))];
}

/// The Monte Carlo reference and what is known of its precision.
struct PopulationReference {
  ShapeModel model;       ///< mean and first modes of the M grids (in the frame of the pipeline's mean)
  nlohmann::json report;  ///< sizes, timings, half-split precision, sampling spread of N-subject cohorts
};

/// Builds the reference for a cohort of `n` subjects whose pipeline mean is `frame` (the reference is
/// moved onto it rigidly); `exclude` holds the cohort's own seeds.
/// On a farm (`farm`), the other processes return an empty reference after the chain.
inline PopulationReference BuildPopulationReference(const PopulationReferenceOptions& o, int n,
                                                    const Eigen::VectorXd& frame,
                                                    const std::set<std::uint64_t>& exclude,
                                                    const IcpTarget& target, const LandmarkSet& landmarks,
                                                    const PipelineOptions& options,
                                                    const ChainFarm& farm = {}) {
  std::string why;
  if (!o.IsValid(&why)) throw std::invalid_argument("population reference: " + why);
  PopulationReference ref;
  ChainGrids grids =
      PopulationThroughChain(o.seed, o.subjects, exclude, target, landmarks, options, "reference", farm);
  const bool with_pool = o.pool >= n && o.pool != 0;
  if (farm.runner != nullptr && !farm.runner->IsLeader()) {  // the pool's farm too, then nothing
    if (with_pool)
      PopulationThroughChain(datasets::Mix64(o.seed), o.pool, exclude, target, landmarks, options,
                             "independent pool", farm);
    return ref;
  }
  double t = Now();
  AlignRowsToTheirMean(options.procrustes_iterations, frame, &grids.rows);
  ShapeModelOptions keep;
  keep.max_modes = 50;
  ref.model = BuildShapeModel(grids.rows, keep, "reference population");
  ref.report = {{"subjects", grids.rows.rows()},        {"seed", o.seed},
                {"cohort_seeds_known", exclude.size()}, {"cohort_seeds_met_and_skipped", grids.seeds_skipped},
                {"chain_failures", grids.failed},       {"chain_wall_s", grids.wall_s},
                {"chain_cpu_s", grids.cpu_s},           {"threads", omp_get_max_threads()}};
  // Precision of the reference itself: its two halves (even / odd rows) against each other. Each half's
  // error is about the split's figure / sqrt(2), the whole reference's about half of it.
  keep.max_modes = o.modes;
  const Eigen::Index h = grids.rows.rows() / 2;
  const ShapeModel even = BuildShapeModel(grids.rows(Eigen::seqN(0, h, 2), Eigen::all), keep, "even half");
  const ShapeModel odd = BuildShapeModel(grids.rows(Eigen::seqN(1, h, 2), Eigen::all), keep, "odd half");
  ref.report["half_split"] = {{"mean_rms_mm", RmsMm(even.mean, odd.mean)},
                              {"largest_angle_deg_k1_to_k", AnglesForEachK(even, odd, o.modes)}};
  grids.rows.resize(0, 0);
  ref.report["pca_wall_s"] = Now() - t;
  if (!with_pool) return ref;

  // Sampling spread of an N-subject cohort: random cohorts of n from an independent pool of true grids,
  // their mean and modes against the reference.
  ChainGrids pool = PopulationThroughChain(datasets::Mix64(o.seed), o.pool, exclude, target, landmarks,
                                           options, "independent pool", farm);
  AlignRowsToTheirMean(options.procrustes_iterations, frame, &pool.rows);
  std::mt19937_64 rng(o.seed ^ static_cast<std::uint64_t>(n));
  const int pool_size = static_cast<int>(pool.rows.rows());
  std::vector<int> order(static_cast<std::size_t>(pool_size));
  std::vector<double> mean_rms;
  std::vector<std::vector<double>> angles(static_cast<std::size_t>(o.modes));
  for (int c = 0; c < o.cohorts; ++c) {
    for (int i = 0; i < pool_size; ++i) order[i] = i;
    std::shuffle(order.begin(), order.end(), rng);
    Eigen::MatrixXd cohort(n, pool.rows.cols());
    for (int i = 0; i < n; ++i) cohort.row(i) = pool.rows.row(order[i]);
    AlignRowsToTheirMean(options.procrustes_iterations, ref.model.mean, &cohort);
    const ShapeModel m = BuildShapeModel(cohort, keep, "pool cohort");
    mean_rms.push_back(RmsMm(m.mean, ref.model.mean));
    const std::vector<double> a = AnglesForEachK(m, ref.model, o.modes);
    for (std::size_t k = 0; k < a.size(); ++k) angles[k].push_back(a[k]);
  }
  nlohmann::json per_k = nlohmann::json::array();
  for (std::size_t k = 0; k < angles.size() && !angles[k].empty(); ++k)
    per_k.push_back(
        {{"k", k + 1}, {"median_deg", Quantile(angles[k], 0.5)}, {"p90_deg", Quantile(angles[k], 0.9)}});
  ref.report["sampling_of_n_subject_cohorts"] = {
      {"n", n},
      {"pool", pool_size},
      {"cohorts", o.cohorts},
      {"pool_chain_wall_s", pool.wall_s},
      {"mean_to_reference_mean_rms_mm",
       {{"median", Quantile(mean_rms, 0.5)}, {"p95", Quantile(mean_rms, 0.95)}}},
      {"largest_angle_to_reference", per_k}};
  return ref;
}

}  // namespace pectus::bench
