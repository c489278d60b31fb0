// model_benchmark: the pipeline's results against the virtual scanner's ground truth. Each subject's true
// surface is put through the same pose and grid as the pipeline gave its scan ("same grid"); the
// population's exact mean and its covariance (to first order: the Jacobian of the whole chain along every
// column of the generator's covariance root) are put through the pipeline's registration and resampling.
#pragma once

#include <Eigen/SVD>
#include <filesystem>
#include <iostream>
#include <nlohmann/json.hpp>
#include <random>

#include "datasets/chest_landmarks.h"
#include "datasets/chest_population.h"
#include "datasets/surface_query.h"
#include "registration/landmark_alignment.h"
#include "shape/io/landmark_io.h"
#include "shape/io/mesh_io.h"
#include "shape/io/stanford_conf.h"
#include "shape/model/cohort_pipeline.h"
#include "shape/model/shape_grid.h"

namespace pectus::bench {

/// The true skin of a subject (truth/surface.ply, scan frame) in the pipeline's reference frame: into the
/// frame of the merge's anchor sweep (whose tracker error the merged scan keeps), then by
/// T_reference_subject.
inline TriangleMesh TrueSurfaceInReferenceFrame(const std::filesystem::path& cohort,
                                                const nlohmann::json& s) {
  const std::filesystem::path dir = cohort / s["name"].get<std::string>();
  TriangleMesh truth = ReadMesh(dir / "truth/surface.ply");
  const std::string anchor = s["sweep_files"][0];
  for (const ScanPose& p : ReadStanfordConf(dir / "truth/poses.conf")) {
    if (std::filesystem::path(p.file).filename() == anchor)
      TransformInPlace(Similarity3::FromRigid(p.T_common_scan.inverse()), &truth);
  }
  Eigen::Matrix4d T;
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) T(r, c) = s["T_reference_subject"][r][c];
  }
  TransformInPlace(Similarity3::FromMatrix(T, "T_reference_subject"), &truth);
  return truth;
}

/// Principal angles (degrees) between the spans of the first k columns of A and B (orthonormal columns).
inline Eigen::VectorXd PrincipalAnglesDeg(const Eigen::MatrixXd& A, const Eigen::MatrixXd& B, int k) {
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(A.leftCols(k).transpose() * B.leftCols(k));
  return svd.singularValues().array().min(1.0).acos() * 180.0 / M_PI;
}

/// `shape` moved rigidly onto `target` (shape vectors, least squares over corresponding vertices).
inline Eigen::VectorXd AlignedTo(const Eigen::VectorXd& target, const Eigen::VectorXd& shape) {
  Points3 x = FromShapeVector(shape);
  const Similarity3 T = UmeyamaAlignment(x, FromShapeVector(target), {}, false, 0.0, "shape");
  for (Eigen::Index k = 0; k < x.rows(); ++k)
    x.row(k) = (T * Eigen::Vector3d(x.row(k).transpose())).transpose();
  return ToShapeVector(x);
}

/// A surface of the generator through the pipeline's chain: tessellated, cut to its ROI + margin (as the
/// sweeps are), registered to the reference, resampled. Returns the grid's shape vector.
inline Eigen::VectorXd ThroughChain(const datasets::ChestSurface& surface, const IcpTarget& reference,
                                    const LandmarkSet& reference_landmarks, const PipelineOptions& options) {
  SubjectOutcome s;
  const TriangleMesh mesh = datasets::Tessellate(surface, 2.0);
  s.landmarks = datasets::TrueLandmarks(surface);
  s.surface.vertices =
      CropToRoi(mesh.vertices, ComputeChestRoi(s.landmarks, options.roi), options.crop_margin_mm);
  RegisterToReference(reference, reference_landmarks, options, &s);
  return ResampleSurface(s.surface, s.landmarks, options.roi, options.resample, "generator surface")
      .shape_vector;
}

inline nlohmann::json CompareWithTruth(const std::filesystem::path& cohort, const std::filesystem::path& out,
                                       const nlohmann::json& report) {
  PipelineOptions options;
  options.resample.grid =
      GridSize{report["grid"]["lateral"].get<int>(), report["grid"]["sternal"].get<int>()};
  // 1. Each subject: its pipeline grid, and its true surface resampled on the same grid.
  std::vector<Eigen::VectorXd> pipeline, truth;
  double sum_subject = 0.0;
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
  }
  const auto n = static_cast<Eigen::Index>(pipeline.size());
  Eigen::MatrixXd P(n, pipeline[0].size()), T(n, pipeline[0].size());
  for (Eigen::Index i = 0; i < n; ++i) P.row(i) = pipeline[i].transpose(), T.row(i) = truth[i].transpose();
  const ShapeModel mp = BuildShapeModel(P), mt = BuildShapeModel(T);
  const Eigen::VectorXd mean_gap = VertexDistances(mp.mean, mt.mean);
  const double m = double(mean_gap.size());
  nlohmann::json j = {{"subjects", n},
                      {"subject_grid_to_true_grid_rms_mm", std::sqrt(sum_subject / double(n))},
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

  // 2. The population: its exact mean and covariance through the chain, against the reference's surface.
  const std::string ref = report["reference"];
  const TriangleMesh ref_surface = ReadMesh(out / "subjects" / ref / "surface.ply");
  const IcpTarget target(ref_surface.vertices.positions, ref_surface.vertices.normals, ref);
  const LandmarkSet ref_landmarks = ReadLandmarks(out / "subjects" / ref / "landmarks.mrk.json");
  const datasets::PopulationModel population = datasets::PopulationModel::Default();
  // The pipeline aligns its grids to their mean (rigid Procrustes); the population's mean is aligned to
  // the pipeline's mean, and each perturbed shape to the population's mean (the linearised alignment).
  const Eigen::VectorXd mu = AlignedTo(
      mp.mean, ThroughChain(datasets::ChestSurface(population.mean), target, ref_landmarks, options));
  const Eigen::VectorXd sample_gap = VertexDistances(mp.mean, mu);
  // Expected sampling error of a mean of n: |e|^2 ~ sum_k lambda_k / n chi^2_1 (lambda from the true
  // surfaces).
  std::mt19937_64 rng(7);
  std::normal_distribution<double> normal;
  std::vector<double> draws(20000);
  for (double& d : draws) {
    double sum = 0.0;
    for (int k = 0; k < mt.num_modes(); ++k) sum += mt.variances[k] / double(n) * std::pow(normal(rng), 2);
    d = std::sqrt(sum / m);
  }
  std::sort(draws.begin(), draws.end());
  j["holds_mean_within_0_2_mm_of_true_mean"] = std::sqrt(mean_gap.squaredNorm() / m) <= 0.2;
  j["population_mean"] = {{"mean_to_population_mean_rms_mm", std::sqrt(sample_gap.squaredNorm() / m)},
                          {"expected_sampling_rms_mm", std::sqrt(mt.total_variance / double(n) / m)},
                          {"sampling_rms_95th_percentile_mm", draws[draws.size() * 95 / 100]},
                          {"holds_within_95th_percentile",
                           std::sqrt(sample_gap.squaredNorm() / m) <= draws[draws.size() * 95 / 100]}};
  // Jacobian of the chain along each column of the covariance root, by central differences of +-0.5 sd.
  const Eigen::MatrixXd A = population.CovarianceRoot();
  const Eigen::VectorXd p0 = datasets::LinearPart(population.mean);
  Eigen::MatrixXd J(mu.size(), A.cols());
  for (Eigen::Index c = 0; c < A.cols(); ++c) {
    Eigen::VectorXd g[2];
    for (int side = 0; side < 2; ++side) {
      datasets::ChestParameters p = population.mean;
      datasets::SetLinearPart(p0 + (side ? 0.5 : -0.5) * A.col(c), &p);
      g[side] = AlignedTo(mu, ThroughChain(datasets::ChestSurface(p), target, ref_landmarks, options));
    }
    J.col(c) = g[1] - g[0];
    if (c % 20 == 0) std::cerr << "jacobian column " << c << " of " << A.cols() << "\n";
  }
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(J, Eigen::ComputeThinU);
  // Modes well above noise: eigenvalue >= 10 x the pipeline's own error variance per shape (the mean
  // squared subject grid to true grid distance times m, mm^2).
  const double noise_mm2 = sum_subject / double(n) * m;
  int k_noise = 0;
  while (k_noise < std::min(8, mp.num_modes()) && mp.variances[k_noise] >= 10.0 * noise_mm2) ++k_noise;
  if (k_noise > 0) {
    const double pipeline_deg = PrincipalAnglesDeg(mp.basis, svd.matrixU(), k_noise).maxCoeff();
    j["modes_well_above_noise"] = {{"noise_variance_mm2", noise_mm2},
                                   {"k", k_noise},
                                   {"largest_principal_angle_to_population_deg", pipeline_deg},
                                   {"largest_principal_angle_same_subjects_true_surfaces_deg",
                                    PrincipalAnglesDeg(mp.basis, mt.basis, k_noise).maxCoeff()},
                                   {"sampling_only_angle_true_surfaces_to_population_deg",
                                    PrincipalAnglesDeg(mt.basis, svd.matrixU(), k_noise).maxCoeff()},
                                   {"holds", pipeline_deg <= 10.0}};
  }
  nlohmann::json population_modes = nlohmann::json::array();
  for (int k = 1; k <= std::min(8, mp.num_modes()); ++k) {
    population_modes.push_back(
        {{"k", k},
         {"largest_angle_pipeline_deg", PrincipalAnglesDeg(mp.basis, svd.matrixU(), k).maxCoeff()},
         {"largest_angle_true_surfaces_deg", PrincipalAnglesDeg(mt.basis, svd.matrixU(), k).maxCoeff()},
         {"population_eigenvalue_mm2", std::pow(svd.singularValues()[k - 1], 2)},
         {"pipeline_eigenvalue_mm2", mp.variances[k - 1]}});
  }
  j["modes_vs_population"] = population_modes;
  return j;
}

}  // namespace pectus::bench
