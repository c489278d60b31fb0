// pectus registration benchmark (issue 4). Prints one JSON object with three parts:
//
//   speed   pectus ICP against PCL (IterativeClosestPointWithNormals) and Open3D (registration_icp,
//           point-to-plane, run by scripts/peers/open3d_icp.py with /usr/bin/python3) on the same two
//           ~100k-point chest scans, same normals (precomputed once, timed apart), same start pose. Peers run
//           twice: plain (one gate, every point) and coarse to fine (pectus's own stages). Reported: time,
//           rotation and translation error against the truth, and the time ratios.
//   pairs   seeded trials of chest scan pairs (0.2 mm surface noise, the second scan's frame off by up to
//           10 degrees and 30 mm, 3 mm landmark noise per axis): the fraction within 0.05 degrees and 0.1
//           mm, and whether every other trial reported failure.
//   bunny   Stanford bunny sweep pairs (45 and 90 degrees apart) from disturbed bun.conf poses: RMS
//           distance to the published placement, how well the scans fit at either placement, the
//           conditioning of the pair's problem, and where the peers converge from the same starts.
//   process (issue 13) whole processes: `pectus register` against Open3D's and PCL's point-to-plane ICP
//           as programs (scripts/peers/open3d_icp.py; this program with --pcl-peer) from the same start
//           on chest pairs (landmark start) and the bunny pairs: time and accuracy ratios per pair.
//           --pectus-before PECTUS adds another build's `pectus` (before a change) to the same run.
//           --process-runs N (default 3): every command runs N times, round robin (each round in its
//           own seeded order, so that no program always follows the same one), and its times are the
//           medians (a single run of a 0.2 s process on a shared VM varies by a third).
//
// The chest scans come from the virtual scanner (pectus::datasets: merged sweeps of a population subject)
// when that library is built, else from the analytic surface of tests/registration/synthetic_chest.h.
//
//   floor   (opt-in) what limits ICP's accuracy: AlignIcp with one option changed at a time, and the peers
//           with every point, on the speed pair, chest pairs and bunny pairs
//           (registration_benchmark_floor.h).
//
//   registration_benchmark [--speed] [--pairs] [--bunny] [--process] [--floor] [--trials N]
//                          [--icp-only-trials N] [--repeat N] [--process-pairs N] [--process-runs N]
//                          [--floor-pairs N]
//                          [--pectus-before PECTUS] [--no-peers]
//   (no part named: all but floor). Every time is given as wall and CPU seconds (the process's CPU time, all
//   threads), with the load average before and after; "acceptance" at the end checks each line of issue 4.
// The parts live in registration_benchmark_{data,peers,speed,pairs,bunny}.h, each included once here.
// The peers first: Eigen is then first read inside their PCL headers' warning pragma (see there).
#include "tests/benchmarks/registration_benchmark_peers.h"
// The others.
#include <omp.h>
#include <unistd.h>

#include <cstdio>
#include <iostream>
#include <stdexcept>
#include <string>

#include "tests/benchmarks/registration_benchmark_bunny.h"
#include "tests/benchmarks/registration_benchmark_data.h"
#include "tests/benchmarks/registration_benchmark_floor.h"
#include "tests/benchmarks/registration_benchmark_pairs.h"
#include "tests/benchmarks/registration_benchmark_process.h"
#include "tests/benchmarks/registration_benchmark_speed.h"

namespace pectus {
namespace {

// The acceptance lines of issue 4 against the figures above: each with its figure and whether it holds.
json Acceptance(const json& out) {
  json a = json::object();
  if (out.contains("pairs")) {
    const json& w = out["pairs"]["with_landmarks"];
    a["pairs"] = {
        {"line", ">= 99 % of trials within 0.05 deg and 0.1 mm; every other trial reports failure"},
        {"within_fraction", w["within_fraction"]},
        {"trials", w["trials"]},
        {"false_successes", w["silent_bad_fits"]},
        {"holds", w["within_fraction"].get<double>() >= 0.99 && w["silent_bad_fits"].get<int>() == 0}};
  }
  if (out.contains("bunny")) {
    double worst = 0.0;
    bool all_success = true;
    json beyond = json::array();
    int within = 0;
    for (const json& b : out["bunny"]) {
      const double rms = b["rms_to_published_mm_max"].get<double>();
      worst = std::max(worst, rms);
      all_success = all_success && b["success"] == b["starts"];
      if (rms <= 0.3) {
        ++within;
      } else {
        beyond.push_back(
            {{"pair", b["fixed"].get<std::string>() + " <- " + b["moving"].get<std::string>()},
             {"rms_to_published_mm", rms},
             {"median_residual_at_published_mm", b["fit_at_published_1mm"]["median_abs_point_to_plane_mm"]},
             {"median_residual_at_pectus_mm", b["fit_at_pectus_1mm"]["median_abs_point_to_plane_mm"]}});
      }
    }
    a["bunny"] = {{"line", "bunny sweep pairs back to <= 0.3 mm RMS of the published placement"},
                  {"pairs", out["bunny"].size()},
                  {"pairs_within", within},
                  {"worst_rms_mm", worst},
                  {"pairs_beyond", beyond},
                  {"every_start_reported_success", all_success},
                  {"holds", worst <= 0.3 && all_success}};
  }
  if (out.contains("process")) {
    // Issue 13: as accurate as Open3D's and PCL's point-to-plane ICP on every chest and bunny pair, at
    // least 8x faster than Open3D and 3x faster than PCL, whole process. Said per peer set-up.
    const json& summary = out["process"]["summary"];
    json lines = json::object();
    for (const auto& [peer, q] : summary.items()) {
      const double need = peer.rfind("open3d", 0) == 0 ? 8.0 : 3.0;
      const bool fast = q["wall_over_pectus_min"].get<double>() >= need;
      const bool accurate = q["pairs_where_the_peer_is_closer"].empty();
      lines[peer] = {
          {"needed_speed_ratio", need},
          {"wall_over_pectus_min", q["wall_over_pectus_min"]},
          {"cpu_over_pectus_min", q["cpu_over_pectus_min"]},
          {"speed_holds", fast},
          {"pectus_as_accurate_on_every_pair", accurate},
          {"pairs_where_the_peer_is_closer", q["pairs_where_the_peer_is_closer"]},
          {"pairs_where_the_peer_is_closer_in_rms_displacement", q["pairs_where_the_peer_is_closer_in_rms"]},
          {"holds", fast && accurate}};
    }
    a["process"] = {{"line",
                     "equal or better accuracy than Open3D's and PCL's point-to-plane ICP on the chest and "
                     "bunny pairs, >= 8x faster than Open3D and >= 3x faster than PCL, whole process"},
                    {"peers", lines}};
  }
  if (out.contains("speed")) {
    const json& sp = out["speed"];
    json speed = {{"line",
                   "two 100k-point scans aligned in <= 0.15 s; PCL and Open3D >= 3x slower at equal or "
                   "better accuracy"},
                  {"pectus_seconds_median", sp["pectus"]["seconds_median"]},
                  {"pectus_cpu_seconds_median", sp["pectus"]["cpu_seconds_median"]},
                  {"pectus_1_thread_seconds_median", sp["pectus_1_thread"]["seconds_median"]},
                  {"time_holds", sp["pectus"]["seconds_median"].get<double>() <= 0.15}};
    // The ratio line, said per comparison (no blanket answer): each peer set-up with its speed ratio and
    // pectus's accuracy in rotation and in translation, what holds and what does not. The line names the
    // peers as documented; the staged set-ups are our stronger, extra peers.
    if (sp.contains("comparisons")) {
      bool documented = true, staged = true;
      for (const auto& [peer, q] : sp["comparisons"].items()) {
        const double ratio = q["wall_time_over_pectus"];
        const bool fast = ratio >= 3.0, rot = q["rotation_deg"]["pectus_as_accurate"],
                   trans = q["translation_mm"]["pectus_as_accurate"];
        char text[512];
        std::snprintf(
            text, sizeof text,
            "%s: %.1fx pectus's wall time (%.1fx CPU) -> %s; rotation %.4f deg (pectus %.4f) -> %s; "
            "translation %.4f mm (pectus %.4f) -> %s",
            q["peer"].get<std::string>().c_str(), ratio, q["cpu_time_over_pectus"].get<double>(),
            fast ? ">= 3x holds" : "< 3x, does not hold", q["rotation_deg"]["peer"].get<double>(),
            q["rotation_deg"]["pectus"].get<double>(), rot ? "pectus as accurate" : "the peer is closer",
            q["translation_mm"]["peer"].get<double>(), q["translation_mm"]["pectus"].get<double>(),
            trans ? "pectus as accurate" : "the peer is closer");
        speed["comparisons"][peer] = {{"text", text},
                                      {"speed_ratio_at_least_3", fast},
                                      {"pectus_as_accurate_in_rotation", rot},
                                      {"pectus_as_accurate_in_translation", trans},
                                      {"holds", fast && rot && trans}};
        bool& group = peer.find("_plain") != std::string::npos ? documented : staged;
        group = group && fast && rot && trans;
      }
      speed["ratio_line_holds_against_the_peers_as_documented"] = documented;
      speed["ratio_line_holds_against_the_peers_through_pectus_stages"] = staged;
    }
    a["speed"] = speed;
  }
  return a;
}

int Main(int argc, char** argv) {
  if (argc == 8 && std::string(argv[1]) == "--pcl-peer") return PclPeer(argv + 2);
  bool speed = false, pairs = false, bunny = false, peers = true, process = false, floor = false;
  int trials = 200, icp_only_trials = 50, repeat = 5, process_pairs = 5, process_runs = 3, floor_pairs = 6;
  std::string pectus_before;
  std::string command = "registration_benchmark";
  for (int i = 1; i < argc; ++i) command += std::string(" ") + argv[i];
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&]() {
      if (i + 1 >= argc) throw std::runtime_error(a + " needs a value");
      return std::stoi(argv[++i]);
    };
    if (a == "--speed") {
      speed = true;
    } else if (a == "--pairs") {
      pairs = true;
    } else if (a == "--bunny") {
      bunny = true;
    } else if (a == "--process") {
      process = true;
    } else if (a == "--floor") {
      floor = true;
    } else if (a == "--floor-pairs") {
      floor_pairs = value();
    } else if (a == "--process-pairs") {
      process_pairs = value();
    } else if (a == "--process-runs") {
      process_runs = value();
    } else if (a == "--pectus-before") {
      if (i + 1 >= argc) throw std::runtime_error(a + " needs a value");
      pectus_before = argv[++i];
    } else if (a == "--no-peers") {
      peers = false;
    } else if (a == "--trials") {
      trials = value();
    } else if (a == "--icp-only-trials") {
      icp_only_trials = value();
    } else if (a == "--repeat") {
      repeat = value();
    } else {
      std::cerr << "usage: registration_benchmark [--speed] [--pairs] [--bunny] [--process] [--floor] "
                   "[--trials N] [--icp-only-trials N] [--repeat N] [--process-pairs N] [--process-runs N] "
                   "[--floor-pairs N] "
                   "[--pectus-before PECTUS] [--no-peers]\n";
      return 2;
    }
  }
  if (!speed && !pairs && !bunny && !process && !floor) speed = pairs = bunny = process = true;
  if ((bunny || process || floor) &&
      !testing_support::HaveSharedFile("registration_benchmark", testing_support::kBunnyConf))
    return 3;
  const auto t0 = Clock::now();
  const double c0 = CpuSeconds();
  json out;
  out["command"] = command;
  out["machine"] = {{"cpu", CpuModel()},
                    {"nproc", ::sysconf(_SC_NPROCESSORS_ONLN)},
                    {"openmp_threads", omp_get_max_threads()},
                    {"loadavg_before", FirstLine("/proc/loadavg")}};
  if (speed) out["speed"] = Speed(std::max(1, repeat), peers);
  if (bunny) out["bunny"] = Bunny(5, peers, &out["bunny_loop"]);
  if (pairs) out["pairs"] = Pairs(std::max(1, trials), std::max(0, icp_only_trials));
  if (process)
    out["process"] = Process(std::max(0, process_pairs), true, pectus_before, std::max(1, process_runs));
  if (floor) out["floor"] = Floor(std::max(0, floor_pairs), peers);
  out["machine"]["loadavg_after"] = FirstLine("/proc/loadavg");
  out["total_seconds"] = Since(t0);
  out["total_cpu_seconds"] = CpuSeconds() - c0;
  out["acceptance"] = Acceptance(out);
  std::cout << out.dump(2) << std::endl;
  return 0;
}

}  // namespace
}  // namespace pectus

int main(int argc, char** argv) {
  try {
    return pectus::Main(argc, argv);
  } catch (const std::exception& e) {
    std::cerr << "registration_benchmark: " << e.what() << "\n";
    return 1;
  }
}
