// model_benchmark: the pipeline's results against the virtual scanner's ground truth. Each subject's true
// surface is put through the same pose and grid as the pipeline gave its scan ("same grid"). The
// generator's population is a Monte Carlo reference (model_benchmark_population.h): M subjects of
// PopulationModel::Default() through the pipeline's own chain (tessellate, crop, register to the cohort's
// reference subject, resample on their landmark grid), aligned by rigid generalized Procrustes as the
// pipeline aligns its grids; its mean and modes are the population's. (It replaced a linearised reference,
// the generator's mean shape put once through the chain plus its Jacobian, which is biased: the chain is
// nonlinear, so the mean of resampled shapes is not the resampled mean shape; docs/benchmarks/model.md.)
#pragma once

#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <random>
#include <set>
#include <stdexcept>

#include "model_benchmark_chain.h"
#include "model_benchmark_population.h"
#include "registration/pose_error.h"
#include "shape/io/landmark_io.h"
#include "shape/io/mesh_io.h"
#include "shape/io/stanford_conf.h"

namespace pectus::bench {

/// The true skin of a subject (truth/surface.ply, scan frame) in the pipeline's reference frame: into the
/// subject's merged frame by the one rigid motion that best maps every merged sweep's true placement
/// (truth/poses.conf) onto the merge's (`T_subject_sweep` of the report), least squares over every 10th
/// point of every sweep, then by T_reference_subject. The merged frame is a gauge: without a tracker prior
/// it is the first sweep's (tracker error and all), with one it is the tracker's frame moved by the mean
/// of the corrections; either way this motion is what the merge decided about the frame, not about the
/// shape, so it is removed (as merge_grid_benchmark removes it), whatever the merge's convention.
inline TriangleMesh TrueSurfaceInReferenceFrame(const std::filesystem::path& cohort,
                                                const nlohmann::json& s) {
  const std::filesystem::path dir = cohort / s["name"].get<std::string>();
  TriangleMesh truth = ReadMesh(dir / "truth/surface.ply");
  std::map<std::string, Rigid3> true_pose;
  for (const ScanPose& p : ReadStanfordConf(dir / "truth/poses.conf"))
    true_pose[std::filesystem::path(p.file).filename().string()] = p.T_common_scan;
  const auto& files = s["sweep_files"];
  const auto& merged = s["T_subject_sweep"];
  if (merged.size() != files.size())
    throw std::runtime_error(s["name"].get<std::string>() + ": the report has no merge pose for every sweep");
  std::vector<PointCloud> sweeps;
  std::vector<Rigid3> in_truth, in_merge;
  for (std::size_t i = 0; i < files.size(); ++i) {
    const std::string file = files[i].get<std::string>();
    Eigen::Matrix4d M;
    for (int r = 0; r < 4; ++r) {
      for (int c = 0; c < 4; ++c) M(r, c) = merged[i][r][c];
    }
    sweeps.push_back(ReadPointCloud(dir / file));
    in_truth.push_back(true_pose.at(file));
    in_merge.push_back(Rigid3(M));
  }
  TransformInPlace(Similarity3::FromRigid(BestCommonMotion(sweeps, in_truth, in_merge, 10)), &truth);
  Eigen::Matrix4d T;
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) T(r, c) = s["T_reference_subject"][r][c];
  }
  TransformInPlace(Similarity3::FromMatrix(T, "T_reference_subject"), &truth);
  return truth;
}

/// Subject `s`'s generator seed (COHORT/NAME/truth/subject.json; 0 if it has none).
inline std::uint64_t SubjectSeed(const std::filesystem::path& cohort, const nlohmann::json& s) {
  std::ifstream in(cohort / s["name"].get<std::string>() / "truth/subject.json");
  return in ? nlohmann::json::parse(in)["seed"].get<std::uint64_t>() : 0;
}

/// What the population's chain takes from the pipeline's output: the reference subject's surface and
/// landmarks, and the cohort's own seeds (left out of the population).
struct ReferenceChainInputs {
  std::unique_ptr<IcpTarget> target;
  LandmarkSet landmarks;
  std::set<std::uint64_t> cohort_seeds;
};

inline ReferenceChainInputs ReferenceChainInputsOf(const std::filesystem::path& cohort,
                                                   const std::filesystem::path& out,
                                                   const nlohmann::json& report) {
  const std::string ref = report["reference"];
  const TriangleMesh ref_surface = ReadMesh(out / "subjects" / ref / "surface.ply");
  ReferenceChainInputs in{
      std::make_unique<IcpTarget>(ref_surface.vertices.positions, ref_surface.vertices.normals, ref),
      ReadLandmarks(out / "subjects" / ref / "landmarks.mrk.json"),
      {}};
  for (const nlohmann::json& s : report["subjects"]) in.cohort_seeds.insert(SubjectSeed(cohort, s));
  return in;
}

/// The pipeline's grid options and its subjects' grids (rows), from OUT and its report.
inline Eigen::MatrixXd PipelineGrids(const std::filesystem::path& out, const nlohmann::json& report) {
  std::vector<Eigen::VectorXd> rows;
  for (const nlohmann::json& s : report["subjects"]) {
    if (s["ok"].get<bool>())
      rows.push_back(ToShapeVector(
          ReadMesh(out / "subjects" / s["name"].get<std::string>() / "grid.ply").vertices.positions));
  }
  Eigen::MatrixXd P(static_cast<Eigen::Index>(rows.size()), rows.empty() ? 0 : rows[0].size());
  for (std::size_t i = 0; i < rows.size(); ++i) P.row(static_cast<Eigen::Index>(i)) = rows[i].transpose();
  return P;
}

/// Only the Monte Carlo reference of OUT's pipeline (section 2 of CompareWithTruth, on `farm`), its model
/// written to `file` (raw doubles: mean, variances, basis) by the leader: the bytes to compare between
/// runs on different numbers of ranks. JSON on the leader; null on the other processes.
inline nlohmann::json PopulationOnly(const std::filesystem::path& cohort, const std::filesystem::path& out,
                                     const nlohmann::json& report, const PopulationReferenceOptions& o,
                                     const ChainFarm& farm, const std::filesystem::path& file) {
  PipelineOptions options;
  options.resample.grid =
      GridSize{report["grid"]["lateral"].get<int>(), report["grid"]["sternal"].get<int>()};
  const Eigen::MatrixXd P = PipelineGrids(out, report);
  const ShapeModel mp = BuildShapeModel(P);
  const ReferenceChainInputs chain = ReferenceChainInputsOf(cohort, out, report);
  const double t0 = Now();
  const PopulationReference ref = BuildPopulationReference(o, int(P.rows()), mp.mean, chain.cohort_seeds,
                                                           *chain.target, chain.landmarks, options, farm);
  if (farm.runner != nullptr && !farm.runner->IsLeader()) return nullptr;
  std::string bytes;
  auto put = [&](const double* data, Eigen::Index size) {
    bytes.append(reinterpret_cast<const char*>(data), sizeof(double) * static_cast<std::size_t>(size));
  };
  put(ref.model.mean.data(), ref.model.mean.size());
  put(ref.model.variances.data(), ref.model.variances.size());
  put(ref.model.basis.data(), ref.model.basis.size());
  WriteFileAtomically(file, bytes);
  nlohmann::json j = ref.report;
  j["file"] = file.string();
  j["file_bytes"] = bytes.size();
  j["modes"] = ref.model.num_modes();
  j["wall_s"] = Now() - t0;
  j["processes"] = farm.runner != nullptr ? farm.runner->Processes() : 1;
  return j;
}

/// The pipeline's output OUT of COHORT (`report`: OUT/pipeline.json) against the truth: each subject's grid
/// against its true grid, the mean and modes against the same subjects' true surfaces, and against the
/// Monte Carlo population (`reference_options`: its size M, the pool for the sampling spread). JSON.
inline nlohmann::json CompareWithTruth(const std::filesystem::path& cohort, const std::filesystem::path& out,
                                       const nlohmann::json& report,
                                       const PopulationReferenceOptions& reference_options = {}) {
  PipelineOptions options;
  options.resample.grid =
      GridSize{report["grid"]["lateral"].get<int>(), report["grid"]["sternal"].get<int>()};
  // 1. Each subject: its pipeline grid, and its true surface resampled on the same grid.
  std::vector<Eigen::VectorXd> pipeline, truth;
  double sum_subject = 0.0;
  nlohmann::json per_subject = nlohmann::json::array();  // each grid against its truth: RMS and max
  for (const nlohmann::json& s : report["subjects"]) {
    if (!s["ok"].get<bool>()) continue;
    const std::filesystem::path dir = out / "subjects" / s["name"].get<std::string>();
    pipeline.push_back(ToShapeVector(ReadMesh(dir / "grid.ply").vertices.positions));
    const LandmarkSet landmarks = ReadLandmarks(dir / "landmarks.mrk.json");
    truth.push_back(ResampleSurface(TrueSurfaceInReferenceFrame(cohort, s), landmarks, options.roi,
                                    options.resample, s["name"].get<std::string>())
                        .shape_vector);
    const Eigen::VectorXd d = VertexDistances(pipeline.back(), truth.back());
    sum_subject += d.squaredNorm() / double(d.size());
    Eigen::Index worst = 0;
    per_subject.push_back({{"name", s["name"]},
                           {"rms_mm", std::sqrt(d.squaredNorm() / double(d.size()))},
                           {"max_mm", d.maxCoeff(&worst)},
                           {"max_at_vertex", worst}});
  }
  const auto n = static_cast<Eigen::Index>(pipeline.size());
  Eigen::MatrixXd P(n, pipeline[0].size()), T(n, pipeline[0].size());
  for (Eigen::Index i = 0; i < n; ++i) P.row(i) = pipeline[i].transpose(), T.row(i) = truth[i].transpose();
  const ShapeModel mp = BuildShapeModel(P), mt = BuildShapeModel(T);
  const Eigen::VectorXd mean_gap = VertexDistances(mp.mean, mt.mean);
  const double m = double(mean_gap.size());
  nlohmann::json j = {{"subjects", n},
                      {"subject_grid_to_true_grid_rms_mm", std::sqrt(sum_subject / double(n))},
                      {"subject_grids_to_true_grids", per_subject},
                      {"mean_to_true_mean_rms_mm", std::sqrt(mean_gap.squaredNorm() / m)},
                      {"mean_to_true_mean_max_mm", mean_gap.maxCoeff()}};
  nlohmann::json same = nlohmann::json::array();
  for (int k = 1; k <= std::min(8, mt.num_modes()); ++k) {
    same.push_back({{"k", k},
                    {"largest_angle_deg", PrincipalAnglesDeg(mp.basis, mt.basis, k).maxCoeff()},
                    {"eigenvalue_pipeline_mm2", mp.variances[k - 1]},
                    {"eigenvalue_truth_mm2", mt.variances[k - 1]}});
  }
  j["modes_vs_same_subjects_true_surfaces"] = same;

  // 2. The population: M subjects through the same chain (same reference subject and options), aligned
  // and modelled as the pipeline does (model_benchmark_population.h), moved onto the pipeline's mean.
  const ReferenceChainInputs chain = ReferenceChainInputsOf(cohort, out, report);
  const IcpTarget& target = *chain.target;
  const LandmarkSet& ref_landmarks = chain.landmarks;
  const std::set<std::uint64_t>& cohort_seeds = chain.cohort_seeds;
  std::vector<std::uint64_t> seed_of;  // of each subject in `truth`
  for (const nlohmann::json& s : report["subjects"]) {
    if (s["ok"].get<bool>()) seed_of.push_back(SubjectSeed(cohort, s));
  }
  // Check of the reference's path: the same subjects drawn again from their seeds and put through the
  // chain as the reference's subjects are, against their true grids (the truth's path). Both are the same
  // surfaces; what differs is the path (tessellation, crop, landmarks, registration).
  std::vector<Eigen::VectorXd> again(truth.size());
#pragma omp parallel for schedule(dynamic)
  for (int i = 0; i < int(truth.size()); ++i) {
    const datasets::ChestSurface surface(
        datasets::SampleSubject(datasets::PopulationModel::Default(), seed_of[i]).parameters);
    again[i] = AlignedTo(truth[i], ThroughChain(surface, target, ref_landmarks, options));
  }
  Eigen::VectorXd again_mean = Eigen::VectorXd::Zero(mt.mean.size());
  double again_sum = 0.0;
  for (std::size_t i = 0; i < truth.size(); ++i) {
    again_mean += again[i] / double(n);
    again_sum += std::pow(RmsMm(again[i], truth[i]), 2);
  }
  j["same_subjects_through_reference_chain_vs_true_grids"] = {
      {"subject_rms_mm", std::sqrt(again_sum / double(n))},
      {"mean_rms_mm", RmsMm(AlignedTo(mt.mean, again_mean), mt.mean)}};
  const PopulationReference population = BuildPopulationReference(
      reference_options, int(n), mp.mean, cohort_seeds, target, ref_landmarks, options);
  const ShapeModel& mc = population.model;
  j["population_reference"] = population.report;
  // The mean: both means are estimates, so |e|^2 ~ sum_k lambda_k (1/N + 1/M) chi^2_1 (lambda of the
  // reference; past its first modes the rest of the trace as one term, its chi^2 averaged out).
  const double pipeline_to_mc = RmsMm(mp.mean, AlignedTo(mp.mean, mc.mean));
  const double factor = 1.0 / double(n) + 1.0 / population.report["subjects"].get<double>();
  const double tail = mc.total_variance - mc.variances.sum();
  std::mt19937_64 rng(7);
  std::normal_distribution<double> normal;
  std::vector<double> draws(20000);
  for (double& d : draws) {
    double sum = tail;
    for (int k = 0; k < mc.num_modes(); ++k) sum += mc.variances[k] * std::pow(normal(rng), 2);
    d = std::sqrt(sum * factor / m);
  }
  std::sort(draws.begin(), draws.end());
  const double p95 = draws[draws.size() * 95 / 100];
  // Where the gap lies: (pipeline mean - reference mean) on the reference's first modes, in standard
  // deviations of that difference (sqrt(lambda_k (1/N + 1/M))); a sample's chance draw shows as a large
  // z on a mode, a bias of the path as a gap outside them.
  const Eigen::VectorXd diff = AlignedTo(mc.mean, mp.mean) - mc.mean;
  nlohmann::json z = nlohmann::json::array();
  Eigen::VectorXd rest = diff;
  for (int k = 0; k < std::min(8, mc.num_modes()); ++k) {
    const double c = mc.basis.col(k).dot(diff);
    z.push_back(c / std::sqrt(mc.variances[k] * factor));
    rest -= c * mc.basis.col(k);
  }
  j["holds_mean_within_0_2_mm_of_true_mean"] = std::sqrt(mean_gap.squaredNorm() / m) <= 0.2;
  j["population_mean"] = {
      {"mean_to_population_mean_rms_mm", pipeline_to_mc},
      {"same_subjects_true_mean_to_population_mean_rms_mm", RmsMm(mt.mean, AlignedTo(mt.mean, mc.mean))},
      {"expected_sampling_rms_mm", std::sqrt(mc.total_variance * factor / m)},
      {"sampling_rms_95th_percentile_mm", p95},
      {"gap_on_population_modes_1_to_8_in_sd", z},
      {"gap_outside_modes_1_to_8_rms_mm", std::sqrt(rest.squaredNorm() / m)},
      {"holds_within_95th_percentile", pipeline_to_mc <= p95}};
  // Modes well above noise: eigenvalue >= 10 x the pipeline's own error variance per shape (the mean
  // squared subject grid to true grid distance times m, mm^2).
  const double noise_mm2 = sum_subject / double(n) * m;
  int k_noise = 0;
  while (k_noise < std::min(8, mp.num_modes()) && mp.variances[k_noise] >= 10.0 * noise_mm2) ++k_noise;
  if (k_noise > 0) {
    const double pipeline_deg = PrincipalAnglesDeg(mp.basis, mc.basis, k_noise).maxCoeff();
    j["modes_well_above_noise"] = {{"noise_variance_mm2", noise_mm2},
                                   {"k", k_noise},
                                   {"largest_principal_angle_to_population_deg", pipeline_deg},
                                   {"largest_principal_angle_same_subjects_true_surfaces_deg",
                                    PrincipalAnglesDeg(mp.basis, mt.basis, k_noise).maxCoeff()},
                                   {"sampling_only_angle_true_surfaces_to_population_deg",
                                    PrincipalAnglesDeg(mt.basis, mc.basis, k_noise).maxCoeff()},
                                   {"holds", pipeline_deg <= 10.0}};
    // What N subjects can resolve at this k, and how precise the reference itself is there.
    const nlohmann::json& r = population.report;
    if (r.contains("sampling_of_n_subject_cohorts")) {
      for (const nlohmann::json& a : r["sampling_of_n_subject_cohorts"]["largest_angle_to_reference"])
        if (a["k"] == k_noise)
          j["modes_well_above_noise"]["sampling_angle_of_n_subject_cohorts_deg"] = {
              {"median", a["median_deg"]}, {"p90", a["p90_deg"]}};
    }
    if (r["half_split"]["largest_angle_deg_k1_to_k"].size() >= std::size_t(k_noise))
      j["modes_well_above_noise"]["reference_half_split_angle_deg"] =
          r["half_split"]["largest_angle_deg_k1_to_k"][k_noise - 1];
  }
  nlohmann::json population_modes = nlohmann::json::array();
  for (int k = 1; k <= std::min({8, mp.num_modes(), mc.num_modes()}); ++k) {
    population_modes.push_back(
        {{"k", k},
         {"largest_angle_pipeline_deg", PrincipalAnglesDeg(mp.basis, mc.basis, k).maxCoeff()},
         {"largest_angle_true_surfaces_deg", PrincipalAnglesDeg(mt.basis, mc.basis, k).maxCoeff()},
         {"population_eigenvalue_mm2", mc.variances[k - 1]},
         {"pipeline_eigenvalue_mm2", mp.variances[k - 1]}});
  }
  j["modes_vs_population"] = population_modes;
  return j;
}

}  // namespace pectus::bench
