// pectus registration benchmark (issue 4), part "speed": pectus ICP against PCL
// (IterativeClosestPointWithNormals) and Open3D (registration_icp, point-to-plane) on the same two
// ~100k-point chest scans, same normals (precomputed once, timed apart), same start pose. Peers run twice:
// plain (one gate, every point) and coarse to fine (pectus's own stages). Included once, by
// registration_benchmark.cc.
#pragma once

#include <unistd.h>

#include <utility>

#include "registration/estimate_normals.h"
#include "registration/icp.h"
#include "tests/benchmarks/registration_benchmark_peers.h"

namespace pectus {
namespace {

json Speed(int repeat, bool peers) {
  std::mt19937_64 rng(20240901);
  const Rigid3 T_true = testing::RandomPose(&rng, 20.0, 100.0);
  ScanPair p = MakeScanPair(20240901);
  MoveFrame(T_true, &p);
  const Eigen::Vector3d c = T_true * Eigen::Vector3d(p.moving.positions.colwise().mean().transpose());
  const Rigid3 start = testing::RandomPose(&rng, 3.0, 10.0, c) * T_true;

  // Normals, once, for everybody (pectus EstimateNormals, k = 12); timed on their own.
  NormalOptions no;
  no.k = 12;
  no.orientation = NormalOrientation::kNone;
  const NormalResult nt = EstimateNormals(p.fixed.positions, no);
  const NormalResult ns = EstimateNormals(p.moving.positions, no);

  json out;
  out["data"] = {{"source", kData},
                 {"target_points", p.fixed.size()},
                 {"source_points", p.moving.size()},
                 {"start_error", ErrorJson(ErrorOf(start, p))},
                 {"normals_seconds_target", nt.timings_s.Total()},
                 {"normals_seconds_source", ns.timings_s.Total()},
                 {"normals",
                  "precomputed once with pectus EstimateNormals (k = 12) and given to every method; "
                  "not in any time below"}};

  // pectus: prepare the target (centre, k-d tree, spacing) and align, both timed; default options. Run
  // with one thread and with every thread; the levels of the last run set the peers' stages.
  IcpResult r;
  auto run_pectus = [&](int threads) {
    omp_set_num_threads(threads);
    std::vector<double> total, prepare, cpu;
    for (int k = 0; k < repeat; ++k) {
      const double c0 = CpuSeconds();
      const auto t0 = Clock::now();
      const IcpTarget target(p.fixed.positions, nt.normals);
      prepare.push_back(Since(t0));
      r = AlignIcp(target, p.moving.positions, Points3(), start);
      total.push_back(Since(t0));
      cpu.push_back(CpuSeconds() - c0);
    }
    json levels = json::array();
    for (const auto& l : r.levels) {
      levels.push_back({{"points", l.source_points},
                        {"gate_mm", l.max_distance_mm},
                        {"iterations", l.iterations},
                        {"tree_searches", l.searches}});
    }
    return json{{"seconds_median", Median(total)},
                {"seconds_best", *std::min_element(total.begin(), total.end())},
                {"cpu_seconds_median", Median(cpu)},
                {"seconds_prepare_target_median", Median(prepare)},
                {"error", ErrorJson(ErrorOf(r.T_target_source, p))},
                {"success", r.success},
                {"iterations", r.iterations},
                {"levels", levels},
                {"rms_mm", r.rms_mm},
                {"runs", repeat},
                {"threads", threads},
                {"timed", "IcpTarget (centring, k-d tree, spacing) + AlignIcp"},
                {"method",
                 "point-to-plane, Cauchy loss, nested random levels, certified correspondence reuse "
                 "(defaults)"}};
  };
  const int threads = omp_get_max_threads();
  out["pectus_1_thread"] = run_pectus(1);
  out["pectus"] = run_pectus(threads);
  omp_set_num_threads(threads);
  std::vector<Stage> stages;
  for (const auto& l : r.levels) {
    stages.push_back(
        {l.max_distance_mm, l.source_points < p.moving.size() ? static_cast<int>(l.source_points) : 0});
  }
  if (!peers) return out;

  const std::vector<Stage> plain = {{15.0, 0}};
  const int peer_repeat = std::max(1, std::min(repeat, 3));
  // A peer's figures with its error against the truth.
  auto scored = [&](const PeerRun& run) {
    json f = run.figures;
    if (f.contains("seconds_median")) f["error"] = ErrorJson(ErrorOf(run.T, p));
    return f;
  };
  const Points3& x_t = p.fixed.positions;
  const Points3& x_s = p.moving.positions;
  out["pcl_plain"] = scored(RunPcl(x_t, nt.normals, x_s, ns.normals, start, plain, 50, peer_repeat));
  out["pcl_staged"] = scored(RunPcl(x_t, nt.normals, x_s, ns.normals, start, stages, 30, peer_repeat));

  const fs::path dir = fs::temp_directory_path() / ("pectus_reg_bench_" + std::to_string(::getpid()));
  WriteOpen3dInputs(dir, x_t, nt.normals, x_s, ns.normals, start);
  out["open3d_plain"] = scored(RunOpen3d(dir, plain, 50, peer_repeat));
  out["open3d_staged"] = scored(RunOpen3d(dir, stages, 30, peer_repeat));
  std::error_code ec;
  fs::remove_all(dir, ec);

  // One comparison per peer and set-up: the ratios of the peer's times to pectus's (wall and CPU,
  // medians), and whether pectus is at least as accurate, in rotation and in translation apart: its error
  // against the truth is at most the peer's, or within 0.001 degrees (rotation) or 0.005 mm (translation)
  // of it (a tenth of the pair tolerances; below that the errors are the noise's, not the method's).
  const json& mine = out["pectus"];
  const double mine_rot = mine["error"]["rotation_deg"], mine_trans = mine["error"]["translation_mm"];
  const std::pair<const char*, const char*> comparisons[] = {
      {"pcl_plain", "PCL IterativeClosestPointWithNormals as documented (one 15 mm gate, every point)"},
      {"open3d_plain", "Open3D registration_icp point-to-plane as documented (one 15 mm gate, every point)"},
      {"pcl_staged", "PCL IterativeClosestPointWithNormals through pectus's coarse-to-fine stages"},
      {"open3d_staged", "Open3D registration_icp point-to-plane through pectus's coarse-to-fine stages"}};
  for (const auto& [peer, what] : comparisons) {
    if (!out[peer].contains("seconds_median")) continue;
    const json& o = out[peer];
    const double rot = o["error"]["rotation_deg"], trans = o["error"]["translation_mm"];
    json& q = out["comparisons"][peer];
    q["peer"] = what;
    q["wall_time_over_pectus"] = o["seconds_median"].get<double>() / mine["seconds_median"].get<double>();
    q["cpu_time_over_pectus"] =
        o["cpu_seconds_median"].get<double>() / mine["cpu_seconds_median"].get<double>();
    q["wall_time_over_pectus_1_thread"] =
        o["seconds_median"].get<double>() / out["pectus_1_thread"]["seconds_median"].get<double>();
    q["rotation_deg"] = {{"pectus", mine_rot}, {"peer", rot}, {"pectus_as_accurate", mine_rot <= rot + 1e-3}};
    q["translation_mm"] = {
        {"pectus", mine_trans}, {"peer", trans}, {"pectus_as_accurate", mine_trans <= trans + 5e-3}};
  }
  return out;
  return out;
}

}  // namespace
}  // namespace pectus
