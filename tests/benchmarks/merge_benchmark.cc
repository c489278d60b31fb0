// Benchmark of `pectus merge` on the real Stanford bunny: every sweep but bun000 starts from its bun.conf
// pose disturbed by a seeded random rotation up to 3 degrees and translation up to 5 mm (about the
// sweep's centroid); prints, per seed, each sweep's RMS point displacement from its published placement
// and the time of each stage, as JSON.
//   build/tests/benchmarks/merge_benchmark [SEEDS=5]
#include <chrono>
#include <cstdio>
#include <random>

#include "shape/io/mesh_io.h"
#include "shape/io/stanford_conf.h"
#include "shape/sweep_merge.h"

using namespace pectus;

namespace {

Rigid3 DisturbAbout(std::mt19937_64* rng, const Eigen::Vector3d& c, double max_deg, double max_mm) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Eigen::Vector3d axis(u(*rng), u(*rng), u(*rng)), t;
  do t = Eigen::Vector3d(u(*rng), u(*rng), u(*rng)); while (t.norm() > 1.0);
  Rigid3 D = Rigid3::Identity();
  D.linear() = Eigen::AngleAxisd(max_deg * M_PI / 180.0 * std::abs(u(*rng)), axis.normalized()).toRotationMatrix();
  D.translation() = max_mm * t + c - D.linear() * c;
  return D;
}

double RmsDisplacement(const Points3& p, const Rigid3& a, const Rigid3& b) {
  double s = 0;
  for (Eigen::Index i = 0; i < p.rows(); ++i) s += ((a * p.row(i).transpose()) - (b * p.row(i).transpose())).squaredNorm();
  return std::sqrt(s / static_cast<double>(p.rows()));
}

}  // namespace

int main(int argc, char** argv) {
  const int seeds = argc > 1 ? std::atoi(argv[1]) : 5;
  const std::string dir = std::string(PECTUS_SHARED_DIR) + "/datasets/stanford_bunny/";
  std::vector<ScanPose> poses = ReadStanfordConf(dir + "bun.conf");
  ScaleTranslations(1000.0, &poses);
  ReadOptions ro;
  ro.input_units = LengthUnit::kMetre;
  std::vector<PointCloud> sweeps;
  for (const auto& p : poses) sweeps.push_back(ReadPointCloud(dir + p.file, ro));
  double worst = 0;
  std::printf("[\n");
  for (int seed = 0; seed < seeds; ++seed) {
    std::mt19937_64 rng(1000 + seed);
    std::vector<Rigid3> start;
    double start_worst = 0;
    for (std::size_t s = 0; s < sweeps.size(); ++s) {
      const Eigen::Vector3d c = poses[s].T_common_scan * Eigen::Vector3d(sweeps[s].positions.colwise().mean().transpose());
      start.push_back(s == 0 ? poses[s].T_common_scan : DisturbAbout(&rng, c, 3.0, 5.0) * poses[s].T_common_scan);
      start_worst = std::max(start_worst, RmsDisplacement(sweeps[s].positions, start[s], poses[s].T_common_scan));
    }
    const auto t0 = std::chrono::steady_clock::now();
    const SweepMergeResult r = MergeSweeps(sweeps, start);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    std::printf("  {\"seed\": %d, \"seconds\": %.3f, \"normals_s\": %.3f, \"pairwise_s\": %.3f, \"global_s\": %.3f, "
                "\"start_worst_rms_mm\": %.3f, \"rms_displacement_mm\": {",
                1000 + seed, seconds, r.seconds_normals, r.seconds_pairwise, r.seconds_global, start_worst);
    for (std::size_t s = 0; s < sweeps.size(); ++s) {
      const double d = RmsDisplacement(sweeps[s].positions, r.T_world_sweep[s], poses[s].T_common_scan);
      worst = std::max(worst, d);
      std::printf("%s\"%s\": %.3f", s ? ", " : "", poses[s].file.c_str(), d);
    }
    std::printf("}}%s\n", seed + 1 < seeds ? "," : "");
  }
  std::printf("]\n");
  std::fprintf(stderr, "worst RMS displacement over all sweeps and seeds: %.3f mm\n", worst);
  return worst <= 0.3 ? 0 : 1;
}
