// Benchmark of `pectus merge` on the real Stanford bunny (ten sweeps, 362k points). For each seed, EVERY
// sweep starts from its bun.conf pose disturbed by a seeded random rotation up to 3 degrees and a
// translation up to 5 mm (about the sweep's centroid); the merge then brings them back. Printed per seed
// and sweep: the RMS point displacement from the bun.conf placement
//   - "gauge_free": after removing the one common rigid motion that best maps the whole merged set onto
//     bun.conf (least squares over all points). The anchor starts disturbed too, so the absolute frame is
//     not recoverable by any method; this is the acceptance figure.
//   - "anchored": a second run of the same seed with the anchor (bun000) left at its bun.conf pose, no
//     motion removed (bun.conf's own bun000 sits ~0.14 mm off the consensus, so this is stricter).
// and the wall and CPU time of each merge. The start poses of each seed are written as Stanford .conf
// files, so the same disturbance can be fed to the command:
//
//   build/tests/benchmarks/merge_benchmark [--seeds 5] [--workdir /tmp/pectus_merge_benchmark]
//   cd ../shared/datasets/stanford_bunny && pectus merge bun*.ply chin.ply ear_back.ply top*.ply
//       --poses /tmp/pectus_merge_benchmark/start_1000.conf --input-units m --poses-out /tmp/aligned.conf
//       -o /tmp/merged.ply --report /tmp/merge.json
//   build/tests/benchmarks/merge_benchmark --evaluate /tmp/aligned.conf     (the same figures for it)
#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <random>

#include "registration/pose_error.h"
#include "shape/io/mesh_io.h"
#include "shape/io/stanford_conf.h"
#include "shape/surface/merge_sweeps.h"
#include "tests/support/bunny_data.h"

using namespace pectus;

namespace {

Rigid3 DisturbAbout(std::mt19937_64* rng, const Eigen::Vector3d& c, double max_deg, double max_mm) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Eigen::Vector3d axis(u(*rng), u(*rng), u(*rng)), t;
  do t = Eigen::Vector3d(u(*rng), u(*rng), u(*rng));
  while (t.norm() > 1.0);
  Rigid3 D = Rigid3::Identity();
  D.linear() =
      Eigen::AngleAxisd(max_deg * M_PI / 180.0 * std::abs(u(*rng)), axis.normalized()).toRotationMatrix();
  D.translation() = max_mm * t + c - D.linear() * c;
  return D;
}

double RmsDisplacement(const Points3& p, const Rigid3& a, const Rigid3& b) {
  double s = 0;
  for (Eigen::Index i = 0; i < p.rows(); ++i)
    s += ((a * p.row(i).transpose()) - (b * p.row(i).transpose())).squaredNorm();
  return std::sqrt(s / static_cast<double>(p.rows()));
}

double CpuSeconds() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return double(u.ru_utime.tv_sec + u.ru_stime.tv_sec) +
         1e-6 * double(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

struct Figures {
  double worst = 0.0;
  std::string json;
};

// Per-sweep displacement of `placed` from bun.conf, raw or after the best common motion.
Figures Displacements(const std::vector<PointCloud>& sweeps, const std::vector<ScanPose>& poses,
                      const std::vector<Rigid3>& placed, const std::vector<Rigid3>& truth, bool gauge_free) {
  const Rigid3 G = gauge_free ? BestCommonMotion(sweeps, placed, truth) : Rigid3::Identity();
  Figures f;
  f.json = "{";
  for (std::size_t s = 0; s < sweeps.size(); ++s) {
    const double d = RmsDisplacement(sweeps[s].positions, G * placed[s], truth[s]);
    f.worst = std::max(f.worst, d);
    char item[128];
    std::snprintf(item, sizeof item, "%s\"%s\": %.3f", s ? ", " : "", poses[s].file.c_str(), d);
    f.json += item;
  }
  f.json += "}";
  return f;
}

}  // namespace

int main(int argc, char** argv) {
  int seeds = 5;
  std::string workdir = "/tmp/pectus_merge_benchmark", evaluate;
  for (int a = 1; a + 1 < argc; a += 2) {
    const std::string key = argv[a], value = argv[a + 1];
    if (key == "--seeds") seeds = std::atoi(value.c_str());
    if (key == "--workdir") workdir = value;
    if (key == "--evaluate") evaluate = value;
  }
  if (!testing_support::HaveSharedFile("merge_benchmark", testing_support::kBunnyConf)) return 3;
  const testing_support::BunnySweeps bunny = testing_support::ReadBunnySweeps();
  const std::vector<ScanPose>& poses = bunny.poses;
  const std::vector<PointCloud>& sweeps = bunny.sweeps;
  const std::vector<Rigid3>& truth = bunny.placements;
  if (!evaluate.empty()) {
    std::vector<ScanPose> out = ReadStanfordConf(evaluate);
    ScaleTranslations(1000.0, &out);
    std::vector<Rigid3> placed;
    for (const auto& p : poses) {
      auto it = std::find_if(out.begin(), out.end(), [&](const ScanPose& q) { return q.file == p.file; });
      if (it == out.end()) {
        std::fprintf(stderr, "%s has no pose for %s\n", evaluate.c_str(), p.file.c_str());
        return 2;
      }
      placed.push_back(it->T_common_scan);
    }
    const Figures g = Displacements(sweeps, poses, placed, truth, true);
    std::printf("{\"evaluated\": \"%s\", \"gauge_free_rms_mm\": %s, \"worst_mm\": %.3f}\n", evaluate.c_str(),
                g.json.c_str(), g.worst);
    return g.worst <= 0.3 ? 0 : 1;
  }
  std::filesystem::create_directories(workdir);
  double worst_gauge_free = 0, worst_anchored = 0;
  std::printf("[\n");
  for (int seed = 0; seed < seeds; ++seed) {
    std::mt19937_64 rng(1000 + seed);
    std::vector<Rigid3> start;
    std::vector<ScanPose> start_conf;
    double start_worst = 0;
    for (std::size_t s = 0; s < sweeps.size(); ++s) {
      const Eigen::Vector3d c = truth[s] * Eigen::Vector3d(sweeps[s].positions.colwise().mean().transpose());
      start.push_back(DisturbAbout(&rng, c, 3.0, 5.0) * truth[s]);
      start_worst = std::max(start_worst, RmsDisplacement(sweeps[s].positions, start[s], truth[s]));
      start_conf.push_back({poses[s].file, start[s]});
    }
    ScaleTranslations(1e-3, &start_conf);
    WriteStanfordConf(workdir + "/start_" + std::to_string(1000 + seed) + ".conf", start_conf);

    auto t0 = std::chrono::steady_clock::now();
    double c0 = CpuSeconds();
    // The disturbance is a tracker whose stated accuracy is its bound (3 degrees about the centroid, 5 mm).
    SweepMergeOptions tracker;
    tracker.tracker_deg = 3.0;
    tracker.tracker_mm = 5.0;
    tracker.tracker_lever_mm = 0.0;
    const SweepMergeResult r = MergeSweeps(sweeps, start, tracker);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const double cpu = CpuSeconds() - c0;
    const Figures g = Displacements(sweeps, poses, r.T_world_sweep, truth, true);

    std::vector<Rigid3> anchored_start = start;
    anchored_start[0] = truth[0];
    t0 = std::chrono::steady_clock::now();
    SweepMergeOptions anchored;  // no prior: pairwise ICP, then the joint adjustment with bun000 held
    anchored.tracker_deg = anchored.tracker_mm = 0.0;
    const SweepMergeResult ra = MergeSweeps(sweeps, anchored_start, anchored);
    const double seconds_anchored =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const Figures a = Displacements(sweeps, poses, ra.T_world_sweep, truth, false);
    worst_gauge_free = std::max(worst_gauge_free, g.worst);
    worst_anchored = std::max(worst_anchored, a.worst);
    std::printf(
        "  {\"seed\": %d, \"wall_s\": %.2f, \"cpu_s\": %.2f, \"normals_s\": %.2f, \"pairwise_s\": %.2f, "
        "\"global_s\": %.2f, \"start_worst_rms_mm\": %.2f, \"points_in\": %lld, \"points_out\": %lld,\n"
        "   \"gauge_free_rms_mm\": %s, \"worst_gauge_free_mm\": %.3f,\n"
        "   \"anchored_wall_s\": %.2f, \"anchored_rms_mm\": %s, \"worst_anchored_mm\": %.3f}%s\n",
        1000 + seed, seconds, cpu, r.timings_s.Seconds("normals"), r.timings_s.Seconds("pairwise_icp"),
        r.timings_s.Seconds("global_adjustment"), start_worst, (long long)r.points_in,
        (long long)r.points_out, g.json.c_str(), g.worst, seconds_anchored, a.json.c_str(), a.worst,
        seed + 1 < seeds ? "," : "");
    std::fflush(stdout);
  }
  std::printf("]\n");
  std::printf("worst over all sweeps and seeds: gauge-free %.3f mm (acceptance <= 0.3), anchored %.3f mm\n",
              worst_gauge_free, worst_anchored);
  return worst_gauge_free <= 0.3 ? 0 : 1;
}
