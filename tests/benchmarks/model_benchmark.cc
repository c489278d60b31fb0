// Benchmarks and acceptance measurements of the shape model (issue 6), printed as JSON; figures and
// commands in docs/benchmarks/model.md.
//   model_benchmark pca [SUBJECTS=1000]          PCA time (Gram route) against Eigen's SVD and numpy's
//   model_benchmark holefill COHORT OUT [PNG]    hole filling and the profile-fit choice, on the surfaces
//                                                that `pectus pipeline COHORT --out OUT` made
//   model_benchmark cohort COHORT OUT REPORT     the pipeline's mean and modes against the generator's truth
#ifndef PECTUS_HAVE_DATASETS
#include <cstdio>
int main() {
  std::fprintf(stderr, "model_benchmark needs the virtual scanner: configure with the datasets component\n");
  return 2;
}
#else
#include <Eigen/SVD>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>

#include "model_benchmark_truth.h"
#include "shape/io/landmark_io.h"
#include "shape/io/mesh_io.h"
#include "shape/model/hole_fill_validation.h"
#include "shape/model/model_figures.h"
#include "shape/model/shape_model.h"

namespace pectus::bench {
namespace {

namespace fs = std::filesystem;
double Now() { return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(); }

// 1. PCA of N subjects of the generator's population sampled on a 51 x 101 grid (15453 numbers each).
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
  const ShapeModel model = BuildShapeModel(shapes);
  const double gram_s = Now() - t;
  t = Now();
  const Eigen::MatrixXd X = shapes.rowwise() - shapes.colwise().mean();
  const Eigen::BDCSVD<Eigen::MatrixXd> svd(X, Eigen::ComputeThinV);
  const double svd_s = Now() - t;
  const Eigen::VectorXd lambda = svd.singularValues().array().square() / double(n - 1);
  const int k = std::min<int>(20, model.num_modes());
  const double rel = ((model.variances.head(k) - lambda.head(k)).array() / lambda.head(k).array()).abs().maxCoeff();
  // numpy on the same matrix, in the same run.
  const fs::path raw = fs::temp_directory_path() / "pectus_model_benchmark_shapes.f64";
  std::ofstream(raw, std::ios::binary).write(reinterpret_cast<const char*>(X.data()), X.size() * 8);
  const std::string py = "/usr/bin/python3 -c \"import numpy as np,time;X=np.fromfile('" + raw.string() +
                         "').reshape(" + std::to_string(X.cols()) + "," + std::to_string(n) +
                         ").T;t=time.time();np.linalg.svd(X,full_matrices=False);print(time.time()-t)\"";
  double numpy_s = -1.0;
  if (FILE* p = popen(py.c_str(), "r")) {
    if (std::fscanf(p, "%lf", &numpy_s) != 1) numpy_s = -1.0;
    pclose(p);
  }
  fs::remove(raw);
  return {{"subjects", n}, {"numbers_per_shape", shapes.cols()}, {"modes", model.num_modes()},
          {"pectus_gram_pca_s", gram_s}, {"eigen_bdcsvd_s", svd_s}, {"numpy_svd_s", numpy_s},
          {"bdcsvd_over_pectus", svd_s / gram_s}, {"numpy_over_pectus", numpy_s / gram_s},
          {"max_relative_eigenvalue_difference_first_20", rel}};
}

// 2. Hole filling on the pipeline's registered surfaces: three 30 mm disks (centre, left border, bottom
// right corner) removed, resampled, compared with the untouched resampling; and each profile fit's accuracy
// against the true surface on the whole grid.
nlohmann::json HoleFill(const fs::path& cohort, const fs::path& out, const nlohmann::json& report, const fs::path& png) {
  struct Fit {
    std::string name;
    ProfileFitOptions options;
  };
  std::vector<Fit> fits;
  for (int q : {3, 2}) {
    ProfileFitOptions o;
    o.penalty_order = q;
    fits.push_back({"spline (penalty order " + std::to_string(q) + ")", o});
  }
  for (int d : {4, 6, 8, 10}) {
    ProfileFitOptions o;
    o.kind = ProfileFitKind::kPolynomial;
    o.polynomial_degree = d;
    fits.push_back({"polynomial degree " + std::to_string(d), o});
  }
  nlohmann::json rows = nlohmann::json::array();
  for (const Fit& fit : fits) {
    double worst_hole = 0.0, worst_truth = 0.0, sum_truth = 0.0;
    Eigen::Index count = 0;
    int subjects = 0;
    for (const nlohmann::json& s : report["subjects"]) {
      if (!s["ok"].get<bool>()) continue;
      const std::string name = s["name"];
      const TriangleMesh surface = ReadMesh(out / "subjects" / name / "surface.ply");
      const LandmarkSet landmarks = ReadLandmarks(out / "subjects" / name / "landmarks.mrk.json");
      const ChestRoi roi = ComputeChestRoi(landmarks);
      CrossSectionOptions options;
      options.fit = fit.options;
      const HoleFillResult h = ValidateHoleFill(surface, roi, DefaultRemovedDisks(roi, 15.0), options, name);
      worst_hole = std::max(worst_hole, h.max_error_in_disks_mm);
      const TriangleMesh truth = TrueSurfaceInReferenceFrame(cohort, s);
      const DistanceMapResult d = ComputeDistanceMap(h.full.mesh.vertices.positions, truth);
      worst_truth = std::max(worst_truth, d.stats.max_abs);
      sum_truth += d.stats.rms * d.stats.rms * static_cast<double>(d.stats.count);
      count += d.stats.count;
      if (!png.empty() && subjects == 0 && fit.name == fits[0].name) {
        SurfaceMapFigure f;
        f.title = name + ": hole-fill error (holed - untouched), 3 disks of 30 mm";
        f.min = -0.5;
        f.max = 0.5;
        f.up = -roi.sternal;
        TriangleMesh grid = h.holed.mesh;
        WriteSurfaceMapPng(png, grid, h.error_mm, roi.normal, f);
      }
      ++subjects;
    }
    rows.push_back({{"fit", fit.name}, {"subjects", subjects}, {"max_error_in_holes_mm", worst_hole},
                    {"grid_to_truth_rms_mm", std::sqrt(sum_truth / double(std::max<Eigen::Index>(1, count)))},
                    {"grid_to_truth_max_mm", worst_truth}});
    std::cerr << rows.back().dump() << "\n";
  }
  return rows;
}

}  // namespace
}  // namespace pectus::bench

int main(int argc, char** argv) {
  using namespace pectus::bench;
  try {
    const std::string what = argc > 1 ? argv[1] : "pca";
    nlohmann::json result;
    if (what == "pca") {
      result = Pca(argc > 2 ? std::atoi(argv[2]) : 1000);
    } else if (what == "holefill" && argc >= 4) {
      std::ifstream in(fs::path(argv[3]) / "pipeline.json");
      result = HoleFill(argv[2], argv[3], nlohmann::json::parse(in), argc > 4 ? argv[4] : "");
    } else if (what == "cohort" && argc >= 4) {
      std::ifstream in(fs::path(argv[3]) / "pipeline.json");
      result = CompareWithTruth(argv[2], argv[3], nlohmann::json::parse(in));
    } else {
      std::cerr << "usage: model_benchmark pca [N] | holefill COHORT OUT [PNG] | cohort COHORT OUT\n"
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
