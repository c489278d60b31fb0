// Benchmark and figures of the virtual scanner (datasets/): prints JSON with
//   - the time to make, scan and write a cohort of 11 subjects in-process (1 and 2 threads, 3 runs each),
//   - convergence of a sampled cohort's mean and PCA to the true ones for N = 25 ... 800,
//   - every patient row of the CT table rebuilt and measured (worst width, depth, depression error),
//   - sweep residuals against the true surface after the true poses, per noise level,
// and with `--images DIR` writes the pictures of docs/datasets.md.
//   build/tests/benchmarks/synth_benchmark [--images docs/images]
#include <omp.h>
#include <sys/resource.h>

#include <Eigen/Dense>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <string>

#include "datasets/chest_measurement.h"
#include "datasets/chest_population.h"
#include "datasets/scan_writer.h"
#include "datasets/seeding.h"
#include "datasets/surface_query.h"
#include "datasets/synth.h"
#include "datasets/synth_preview.h"
#include "shape/render/colormap.h"
#include "shape/render/plot.h"
#include "tests/support/shared_data.h"

using namespace pectus;
using namespace pectus::datasets;
namespace fs = std::filesystem;

namespace {

double Seconds(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// CPU seconds of this process so far (all threads).
double CpuSeconds() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return static_cast<double>(u.ru_utime.tv_sec + u.ru_stime.tv_sec) +
         1e-6 * (u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

// Makes, scans and writes a cohort as `pectus synth cohort` does (without the population folder); returns
// wall seconds and adds the CPU seconds to *cpu.
double TimeCohort(int subjects, int threads, const fs::path& out, double* cpu) {
  omp_set_num_threads(threads);
  fs::remove_all(out);
  const double cpu0 = CpuSeconds();
  const auto t0 = std::chrono::steady_clock::now();
  CohortOptions o;
  o.subjects = subjects;
  const std::vector<SyntheticSubject> cohort = MakeCohortSubjects(o);
#pragma omp parallel for schedule(dynamic)
  for (int i = 0; i < subjects; ++i) {
    const ScannedSubject s = ScanSubject(cohort[i], o.scan, 0.0, CohortScanSeed(o.seed, i));
    WriteSubjectFolder(s, out / cohort[i].name);
  }
  *cpu = CpuSeconds() - cpu0;
  return Seconds(t0);
}

Eigen::VectorXd Flatten(const Points3& P) { return Eigen::Map<const Eigen::VectorXd>(P.data(), P.size()); }

void Convergence(const fs::path& images) {
  const PopulationModel population = PopulationModel::Default();
  const ShapeGrid grid{21, 41};
  const TrueShapeStatistics st = ComputeTrueShapeStatistics(population, grid, 6);
  const int max_n = 800;
  Eigen::MatrixXd X(max_n, 3 * grid.size());
  for (int i = 0; i < max_n; ++i) {
    const SubjectSample s = SampleSubject(population, DeriveSeed(7, SeedStream::kSubject, i));
    X.row(i) = Flatten(SampleGrid(ChestSurface(s.parameters), grid)).transpose();
  }
  std::printf("  \"convergence\": [\n");
  render::Series mean_series, angle_series;
  mean_series.label = "mean RMS error (mm)";
  angle_series.label = "mode 1 angle (deg x 0.1)";
  angle_series.colour = {214, 39, 40};
  render::Series expected_series;
  expected_series.label = "expected mean error sqrt(tr C / (3m N))";
  expected_series.dashed = true;
  expected_series.markers = false;
  expected_series.colour = {31, 119, 180};
  const int sizes[] = {25, 50, 100, 200, 400, 800};
  for (int n : sizes) {
    const Eigen::MatrixXd Y = X.topRows(n);
    const Eigen::RowVectorXd mean = Y.colwise().mean();
    const double rms =
        (mean.transpose() - Flatten(st.mean)).norm() / std::sqrt(static_cast<double>(Y.cols()));
    const Eigen::BDCSVD<Eigen::MatrixXd> svd(Y.rowwise() - mean, Eigen::ComputeThinV);
    double angle[3], ratio[3];
    for (int j = 0; j < 3; ++j) {
      angle[j] =
          std::acos(std::min(1.0, std::abs(svd.matrixV().col(j).dot(Flatten(st.modes[j]))))) * 180.0 / M_PI;
      ratio[j] = svd.singularValues()(j) * svd.singularValues()(j) / (n - 1) / st.eigenvalues(j);
    }
    std::printf(
        "    {\"n\": %d, \"mean_rms_mm\": %.4f, \"expected_mean_rms_mm\": %.4f, \"mode_angle_deg\": [%.3f, "
        "%.3f, "
        "%.3f], \"eigenvalue_ratio\": [%.3f, %.3f, %.3f]}%s\n",
        n, rms, std::sqrt(st.total_variance / n / static_cast<double>(Y.cols())), angle[0], angle[1],
        angle[2], ratio[0], ratio[1], ratio[2], n == max_n ? "" : ",");
    expected_series.x.push_back(n);
    expected_series.y.push_back(std::sqrt(st.total_variance / n / static_cast<double>(Y.cols())));
    mean_series.x.push_back(n);
    mean_series.y.push_back(rms);
    angle_series.x.push_back(n);
    angle_series.y.push_back(0.1 * angle[0]);
  }
  std::printf("  ],\n");
  if (!images.empty()) {
    render::PlotOptions po;
    po.title = "Sampled cohort vs the generator's true statistics";
    po.x_label = "subjects N";
    po.y_label = "error";
    render::WritePng(render::PlotLines({mean_series, expected_series, angle_series}, po),
                     images / "datasets_convergence.png");
  }
}

void Patients() {
  const std::vector<PatientTableRow> rows =
      ReadPatientTable(testing_support::SharedPath(testing_support::kPatientTable));
  const auto t0 = std::chrono::steady_clock::now();
  std::vector<double> err(rows.size() * 3);
#pragma omp parallel for schedule(dynamic)
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const SyntheticSubject s = MakePatientSubject(rows[i], 7, SubjectOptions{});
    const ChestMeasurement m = MeasureChest(s.ChestWall());
    err[3 * i] = std::abs(m.width_mm - rows[i].width_mm);
    err[3 * i + 1] = std::abs(m.depth_mm - rows[i].depth_mm);
    err[3 * i + 2] = std::abs(m.depression_mm - rows[i].depression_mm);
  }
  double worst[3] = {0, 0, 0};
  for (std::size_t i = 0; i < rows.size(); ++i) {
    for (int k = 0; k < 3; ++k) worst[k] = std::max(worst[k], err[3 * i + k]);
  }
  std::printf(
      "  \"patients\": {\"rows\": %zu, \"seconds\": %.3f, \"worst_error_mm\": {\"width\": %.2e, \"depth\": "
      "%.2e, "
      "\"depression\": %.2e}},\n",
      rows.size(), Seconds(t0), worst[0], worst[1], worst[2]);
}

void SweepResiduals() {
  std::printf("  \"sweep_residuals\": [\n");
  const double noises[] = {0.1, 0.3, 0.5};
  for (double noise : noises) {
    ScanOptions o;
    o.noise_mm = noise;
    const SyntheticSubject subject = MakeSubject(SubjectOptions{}, 7, 0);
    const ChestSurface skin = subject.Skin();
    const Scan scan = SimulateScan(skin, o, 3);
    double sum2 = 0.0, raw2 = 0.0;
    long inliers = 0, outliers = 0;
    for (const Sweep& s : scan.sweeps) {
      for (Eigen::Index i = 0; i < s.cloud.size(); ++i) {
        if (s.truth.outlier[static_cast<std::size_t>(i)]) {
          ++outliers;
          continue;
        }
        ClosestPointOptions c;
        c.initial_uv = Eigen::Vector2d(s.truth.u(i), s.truth.v(i));
        const Eigen::Vector3d p = s.cloud.positions.row(i).transpose();
        const double d = ClosestPoint(skin, s.truth.T_scan_sweep * p, c).distance;
        sum2 += d * d;
        raw2 += (p - s.truth.true_points.row(i).transpose()).squaredNorm();
        ++inliers;
      }
    }
    std::printf(
        "    {\"noise_mm\": %.2f, \"points\": %ld, \"outliers\": %ld, \"rms_to_surface_after_true_pose_mm\": "
        "%.4f, "
        "\"rms_displacement_without_pose_mm\": %.3f}%s\n",
        noise, inliers + outliers, outliers, std::sqrt(sum2 / inliers), std::sqrt(raw2 / inliers),
        noise == 0.5 ? "" : ",");
  }
  std::printf("  ],\n");
}

void Images(const fs::path& dir) {
  fs::create_directories(dir);
  // A normal subject: true skin from the front and obliquely, and its sweeps as tracked and after the true
  // poses.
  const SyntheticSubject normal = MakeSubject(SubjectOptions{}, 7, 0);
  ScanOptions scan;
  const ScannedSubject scanned = ScanSubject(normal, scan, 0.0, CohortScanSeed(7, 0));
  const render::View front = SubjectView(normal, 0.0, 0.0, 480, 480),
                     oblique = SubjectView(normal, 35, -15, 480, 480);
  render::WritePng(render::HStack({render::WithTitle(RenderSkin(normal, front), "front"),
                                   render::WithTitle(RenderSkin(normal, oblique), "oblique")},
                                  8),
                   dir / "datasets_subject.png");
  render::WritePng(
      render::HStack({render::WithTitle(RenderSweeps(scanned.scan, oblique, false), "sweeps as tracked"),
                      render::WithTitle(RenderSweeps(scanned.scan, oblique, true), "after true poses")},
                     8),
      dir / "datasets_sweeps.png");
  // Pectus: a saucer and a cup with torsion, coloured by depression depth on one scale.
  PectusParameters saucer;
  saucer.depth_mm = 30.0;
  PectusParameters cup = saucer;
  cup.type = PectusType::kCup;
  cup.torsion_deg = 20.0;
  cup.centre_x_mm = -10.0;
  const SyntheticSubject a = MakeSubjectWithPectus(SubjectOptions{}, 7, 1, saucer);
  const SyntheticSubject b = MakeSubjectWithPectus(SubjectOptions{}, 7, 1, cup);
  const render::View view = SubjectView(a, 20.0, -10.0, 480, 480);
  render::WritePng(
      render::HStack({render::WithTitle(RenderSkin(a, view, true), "saucer, 30 mm"),
                      render::WithTitle(RenderSkin(b, view, true), "cup, 30 mm, torsion 20 deg"),
                      render::ColorBar(0.0, 30.0, render::Colormap::kViridis, "depression (mm)", 480)},
                     8),
      dir / "datasets_pectus.png");
  // The first three true modes at -3 and +3 standard deviations.
  const PopulationModel population = PopulationModel::Default();
  const TrueShapeStatistics st = ComputeTrueShapeStatistics(population, ShapeGrid{}, 3);
  std::vector<render::Image> rows;
  render::View side = render::View::Oblique(60.0, -10.0, 300, 300);
  Points3 all(0, 3);  // one frame for all six pictures, so that sizes compare
  for (int j = 0; j < 3; ++j) {
    for (double sd : {-3.0, 3.0}) {
      const Points3 g = SampleGrid(ChestSurface(AlongMode(population, st, j, sd)), ShapeGrid{21, 21});
      all.conservativeResize(all.rows() + g.rows(), 3);
      all.bottomRows(g.rows()) = g;
    }
  }
  side.frame = ComputeBounds(all);
  for (int j = 0; j < 3; ++j) {
    std::vector<render::Image> row;
    for (double sd : {-3.0, 3.0}) {
      SyntheticSubject m;
      m.parameters = AlongMode(population, st, j, sd);
      row.push_back(render::WithTitle(RenderSkin(m, side),
                                      "mode " + std::to_string(j + 1) + (sd < 0 ? ", -3 sd" : ", +3 sd")));
    }
    rows.push_back(render::HStack(row, 8));
  }
  render::WritePng(render::VStack(rows, 8), dir / "datasets_modes.png");
}

}  // namespace

int main(int argc, char** argv) {
  if (!testing_support::HaveSharedFile("synth_benchmark", testing_support::kPatientTable)) return 3;
  fs::path images;
  if (argc == 3 && std::string(argv[1]) == "--images") images = argv[2];
  const fs::path out = fs::temp_directory_path() / "pectus_synth_benchmark";
  std::printf("{\n  \"cohort_11\": [\n");
  for (int threads : {1, 2}) {
    for (int run = 0; run < 3; ++run) {
      double cpu = 0.0;
      const double wall = TimeCohort(11, threads, out, &cpu);
      std::printf("    {\"threads\": %d, \"wall_s\": %.3f, \"cpu_s\": %.3f}%s\n", threads, wall, cpu,
                  threads == 2 && run == 2 ? "" : ",");
    }
  }
  std::printf("  ],\n");
  fs::remove_all(out);
  omp_set_num_threads(2);
  SweepResiduals();
  Patients();
  Convergence(images);
  if (!images.empty()) Images(images);
  std::printf("  \"images\": \"%s\"\n}\n", images.string().c_str());
  return 0;
}
