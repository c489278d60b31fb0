// pectus registration benchmark (issue 13), part "process": whole processes, as a user runs them.
// `pectus register` (reads both scans and the landmarks or the start pose, registers, writes the
// transform) against Open3D's registration_icp point-to-plane (scripts/peers/open3d_icp.py: starts Python,
// imports Open3D, reads, registers, prints) and PCL's IterativeClosestPointWithNormals (this program with
// --pcl-peer: reads, registers, writes), the peers from the pose pectus starts from: the landmark pose on
// the chest pairs (the first seeds of the "pairs" part: up to 10 degrees and 30 mm, 3 mm landmark noise),
// the disturbed published pose (seed 1 of the "bunny" part) on the bunny pairs. Every process reads the
// same PLY files: positions (mm) and the normals of EstimateNormals (k = 12). Peers run as documented
// (one 15 mm gate, every point) and staged (gates 20, 5 mm and pectus's last gate, every point each).
// Reported per pair: wall and CPU seconds of each process, rotation and translation error against the
// truth, and each peer's figures over pectus's. Included once, by registration_benchmark.cc.
#pragma once

#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <map>
#include <numeric>
#include <random>
#include <sstream>
#include <tuple>

#include "registration/estimate_normals.h"
#include "registration/icp.h"
#include "registration/landmark_alignment.h"
#include "shape/io/landmark_io.h"
#include "shape/io/mesh_io.h"
#include "shape/io/stanford_conf.h"
#include "tests/benchmarks/registration_benchmark_bunny.h"
#include "tests/benchmarks/registration_benchmark_peers.h"
#include "tests/support/shared_data.h"

namespace pectus {
namespace {

// The pectus command beside this program in the build tree (build/apps/pectus).
std::string PectusCommandPath() {
  return (fs::canonical("/proc/self/exe").parent_path() / ".." / ".." / "apps" / "pectus").string();
}

// One pair as files: fixed.ply, moving.ply (with normals), the truth, the peers' start, and what
// `pectus register` is given besides the scans (landmark files or --initial).
struct ProcessCase {
  std::string name;
  Similarity3 truth;       // T_fixed_moving
  Eigen::Vector3d centre;  // moving scan's centroid, where translation errors are taken
  double gate_mm = 0.0;    // pectus's last gate: 3 x the fixed scan's point spacing
  Points3 moving;          // the moving scan's points, for the RMS displacement from the truth
};

void WriteScans(const fs::path& dir, const Points3& fixed, const Points3& moving, ProcessCase* c) {
  NormalOptions no;
  no.k = 12;
  no.orientation = NormalOrientation::kNone;
  PointCloud f, m;
  f.positions = fixed;
  f.normals = EstimateNormals(fixed, no).normals;
  m.positions = moving;
  m.normals = EstimateNormals(moving, no).normals;
  WritePointCloud(dir / "fixed.ply", f);
  WritePointCloud(dir / "moving.ply", m);
  c->centre = moving.colwise().mean().transpose();
  c->moving = moving;
  c->gate_mm = 3.0 * IcpTarget(f.positions, f.normals).spacing_mm();
}

// A process's figures: times, the pose it wrote, its errors against the truth.
json ProcessFigures(const ProcessTime& t, const fs::path& transform, const ProcessCase& c) {
  if (t.status != 0 || !fs::exists(transform))
    return {{"error", "failed (exit status " + std::to_string(t.status) + ")"}};
  const Similarity3 T = ReadTransformJson(transform);
  const PoseError e = ComparePoses(T, c.truth, c.centre);
  return {{"wall_s", t.wall_s},
          {"cpu_s", t.cpu_s},
          {"rotation_deg", e.rotation_deg},
          {"translation_mm", e.translation_mm},
          {"rms_displacement_mm", RmsDisplacement(c.moving, T, c.truth)}};
}

// Runs every process on the files in `dir` `runs` times, round robin (every command once, then again), so
// that a slow minute of the machine falls on all of them alike, each round in its own order (a seeded
// shuffle): on a VM a process right after a heavy one runs slower (the first `pectus register` after
// PCL's 2.5 s took 0.15 s where the next took 0.11, whichever build it was, with 0.06 s more system time),
// and a fixed order put `pectus` after PCL in every round and Open3D after a light `pectus`
// (docs/benchmarks/registration.md, "Which process runs after which"). Each command's times are the medians
// of its runs (its pose is the same in every run: each program is deterministic). Compares the peers with
// pectus.
json RunProcesses(const fs::path& dir, const ProcessCase& c, const std::string& pectus_args,
                  const std::string& pectus_before, int runs) {
  json out = {{"pair", c.name}, {"last_gate_mm", c.gate_mm}, {"runs", runs}};
  const std::string scans = (dir / "moving.ply").string() + " --to " + (dir / "fixed.ply").string();
  struct Command {
    std::string key, line;
    fs::path transform;
  };
  std::vector<Command> commands;
  auto pectus = [&](const std::string& binary, const std::string& extra, const std::string& key) {
    const fs::path T = dir / (key + ".json");
    commands.push_back({key,
                        binary + " register " + scans + " " + pectus_args + extra + " --transform " +
                            T.string() + " > /dev/null 2>&1",
                        T});
  };
  pectus(PectusCommandPath(), "", "pectus");
  // The same command with the last ICP sample fixed at 30000 points: AlignIcp before issue 13.
  pectus(PectusCommandPath(), " --pose-sd-fraction 0", "pectus_fixed_sample");
  if (!pectus_before.empty()) pectus(pectus_before, "", "pectus_before");
  const std::vector<Stage> plain = {{15.0, 0}}, staged = {{20.0, 0}, {5.0, 0}, {c.gate_mm, 0}};
  for (const auto& [key, stages, iterations] :
       {std::tuple{"open3d_plain", plain, 50}, std::tuple{"open3d_staged", staged, 30}}) {
    const fs::path T = dir / (std::string(key) + ".json");
    commands.push_back({key,
                        "/usr/bin/python3 " + std::string(PECTUS_SOURCE_DIR) +
                            "/scripts/peers/open3d_icp.py " + (dir / "fixed.ply").string() + " " +
                            (dir / "moving.ply").string() + " " + (dir / "init.json").string() +
                            " --stages " + StagesText(stages) + " --max-iterations " +
                            std::to_string(iterations) + " --transform-out " + T.string() + " > /dev/null",
                        T});
  }
  for (const auto& [key, stages, iterations] :
       {std::tuple{"pcl_plain", plain, 50}, std::tuple{"pcl_staged", staged, 30}}) {
    const fs::path T = dir / (std::string(key) + ".json");
    commands.push_back({key,
                        fs::canonical("/proc/self/exe").string() + " --pcl-peer " +
                            (dir / "fixed.ply").string() + " " + (dir / "moving.ply").string() + " " +
                            (dir / "init.json").string() + " " + T.string() + " " + StagesText(stages) + " " +
                            std::to_string(iterations),
                        T});
  }
  std::vector<std::vector<double>> wall(commands.size()), cpu(commands.size());
  std::vector<int> status(commands.size(), 0);
  std::vector<std::size_t> order(commands.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::mt19937_64 shuffle(20261130);  // the same orders in every benchmark run
  for (int run = 0; run < runs; ++run) {
    std::shuffle(order.begin(), order.end(), shuffle);
    for (const std::size_t k : order) {
      if (status[k] != 0) continue;  // a command that failed once is not run again
      const ProcessTime t = RunProcess(commands[k].line);
      status[k] = t.status;
      wall[k].push_back(t.wall_s);
      cpu[k].push_back(t.cpu_s);
    }
  }
  for (std::size_t k = 0; k < commands.size(); ++k) {
    ProcessTime t;
    t.status = status[k];
    t.wall_s = wall[k].empty() ? 0.0 : Median(wall[k]);
    t.cpu_s = cpu[k].empty() ? 0.0 : Median(cpu[k]);
    out[commands[k].key] = ProcessFigures(t, commands[k].transform, c);
    if (t.status == 0) out[commands[k].key]["wall_s_runs"] = wall[k];
  }
  // Each peer over pectus: time ratios, and whether pectus is as accurate (as in the speed part: at most
  // the peer's error, or within 0.001 degrees and 0.005 mm of it).
  // The same for the fixed sample (and a build before the change), under "before".
  for (const char* key : {"pectus", "pectus_fixed_sample", "pectus_before"}) {
    if (!out.contains(key) || !out[key].contains("wall_s")) continue;
    const json mine = out[key];
    const std::string suffix = std::string(key) == "pectus" ? "" : std::string("_") + key;
    for (const char* peer : {"open3d_plain", "open3d_staged", "pcl_plain", "pcl_staged"}) {
      json& q = out[peer];
      if (!q.contains("wall_s")) continue;
      json& r = suffix.empty() ? q : q["before"][key];
      r["wall_over_pectus"] = q["wall_s"].get<double>() / mine["wall_s"].get<double>();
      r["cpu_over_pectus"] = q["cpu_s"].get<double>() / mine["cpu_s"].get<double>();
      r["pectus_as_accurate"] =
          mine["rotation_deg"].get<double>() <= q["rotation_deg"].get<double>() + 1e-3 &&
          mine["translation_mm"].get<double>() <= q["translation_mm"].get<double>() + 5e-3;
      // The RMS over the moving scan's points of the distance from the true placement combines both (the
      // bunny part's figure).
      r["pectus_as_accurate_in_rms"] =
          mine["rms_displacement_mm"].get<double>() <= q["rms_displacement_mm"].get<double>() + 5e-3;
    }
  }
  return out;
}

json Process(int chest_pairs, bool bunny, const std::string& pectus_before, int runs) {
  // PECTUS_PROCESS_DIR keeps each pair's files there (DIR/seed1000, ..., DIR/bun000_bun045, ...; each with
  // truth.json), to profile a process or try an option by hand.
  const char* keep = std::getenv("PECTUS_PROCESS_DIR");
  const fs::path dir = keep
                           ? fs::path(keep)
                           : fs::temp_directory_path() / ("pectus_reg_process_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  json rows = json::array();
  // Chest pairs: the "pairs" part's first seeds, landmarks with 3 mm noise; the peers start where pectus's
  // landmark step puts the moving scan.
  for (int k = 0; k < chest_pairs; ++k) {
    const auto seed = static_cast<std::uint64_t>(1000 + k);
    const NoisyChestPair noisy = MakeNoisyChestPair(seed);
    const ScanPair& p = noisy.pair;
    const LandmarkSet& lf = noisy.fixed_landmarks;
    const LandmarkSet& lm = noisy.moving_landmarks;
    ProcessCase c;
    c.name = "chest seed " + std::to_string(seed);
    c.truth = Similarity3::FromRigid(p.T_true);
    const fs::path at = keep ? dir / ("seed" + std::to_string(seed)) : dir;
    fs::create_directories(at);
    WriteScans(at, p.fixed.positions, p.moving.positions, &c);
    WriteLandmarks(at / "fixed.csv", lf);
    WriteLandmarks(at / "moving.csv", lm);
    WriteTransformJson(at / "init.json", AlignLandmarks(lm, lf).T_target_source);
    WriteTransformJson(at / "truth.json", c.truth);
    rows.push_back(RunProcesses(at, c,
                                "--moving-landmarks " + (at / "moving.csv").string() + " --fixed-landmarks " +
                                    (at / "fixed.csv").string(),
                                pectus_before, runs));
    std::cerr << "process: " << c.name << "\n";
  }
  if (bunny) {
    const fs::path data = testing_support::BunnyDirectory();
    ReadOptions metres;
    metres.input_units = LengthUnit::kMetre;
    metres.warn_units = false;
    std::vector<ScanPose> poses = ReadStanfordConf(data / "bun.conf");
    ScaleTranslations(1000.0, &poses);
    std::map<std::string, Rigid3> pose;
    for (const ScanPose& s : poses) pose[s.file] = s.T_common_scan;
    for (const auto& [fixed_name, moving_name] : kBunnyPairs) {
      const PointCloud fixed = ReadPointCloud(data / fixed_name, metres);
      const PointCloud moving = ReadPointCloud(data / moving_name, metres);
      const Rigid3 published = pose.at(fixed_name).inverse() * pose.at(moving_name);
      std::mt19937_64 rng(1);
      const Eigen::Vector3d centre =
          published * Eigen::Vector3d(moving.positions.colwise().mean().transpose());
      const Rigid3 start = testing::RandomPose(&rng, 5.0, 10.0, centre) * published;
      ProcessCase c;
      c.name = fixed_name.substr(0, 6) + " <- " + moving_name.substr(0, 6);
      c.truth = Similarity3::FromRigid(published);
      const fs::path at = keep ? dir / (fixed_name.substr(0, 6) + "_" + moving_name.substr(0, 6)) : dir;
      fs::create_directories(at);
      WriteScans(at, fixed.positions, moving.positions, &c);
      WriteTransformJson(at / "init.json", Similarity3::FromRigid(start));
      WriteTransformJson(at / "truth.json", c.truth);
      rows.push_back(RunProcesses(at, c, "--initial " + (at / "init.json").string(), pectus_before, runs));
      std::cerr << "process: bunny " << c.name << "\n";
    }
  }
  std::error_code ec;
  if (!keep) fs::remove_all(dir, ec);
  // Per peer: the smallest and median time ratios, and the pairs where pectus is not as accurate.
  json summary = json::object();
  for (const char* peer : {"open3d_plain", "open3d_staged", "pcl_plain", "pcl_staged"}) {
    std::vector<double> wall, cpu;
    json closer = json::array(), closer_rms = json::array();
    std::map<std::string, json> closer_before;
    for (const json& r : rows) {
      if (!r[peer].contains("wall_over_pectus")) continue;
      wall.push_back(r[peer]["wall_over_pectus"]);
      cpu.push_back(r[peer]["cpu_over_pectus"]);
      if (!r[peer]["pectus_as_accurate"].get<bool>()) closer.push_back(r["pair"]);
      if (!r[peer]["pectus_as_accurate_in_rms"].get<bool>()) closer_rms.push_back(r["pair"]);
      if (!r[peer].contains("before")) continue;
      for (const auto& [key, b] : r[peer]["before"].items()) {
        if (!closer_before.count(key)) closer_before[key] = json::array();
        if (!b["pectus_as_accurate"].get<bool>()) closer_before[key].push_back(r["pair"]);
      }
    }
    if (wall.empty()) continue;
    summary[peer] = {{"pairs", wall.size()},
                     {"wall_over_pectus_min", *std::min_element(wall.begin(), wall.end())},
                     {"wall_over_pectus_median", Median(wall)},
                     {"cpu_over_pectus_min", *std::min_element(cpu.begin(), cpu.end())},
                     {"cpu_over_pectus_median", Median(cpu)},
                     {"pairs_where_the_peer_is_closer", closer},
                     {"pairs_where_the_peer_is_closer_in_rms", closer_rms}};
    for (const auto& [key, list] : closer_before)
      summary[peer]["before"][key]["pairs_where_the_peer_is_closer"] = list;
  }
  return {{"pairs", rows},
          {"summary", summary},
          {"pectus", PectusCommandPath()},
          {"timed", "each command as a whole process (wall; CPU of the process and its children)"}};
}

// --pcl-peer FIXED MOVING INIT OUT STAGES ITERATIONS: PCL's ICP as its own process (reads the PLY files
// and the start pose, runs the stages, writes T_target_source to OUT).
int PclPeer(char** argv) {
  const PointCloud fixed = ReadPointCloud(argv[0]), moving = ReadPointCloud(argv[1]);
  const Rigid3 start = ReadTransformJson(argv[2]).RigidPart();
  std::vector<Stage> stages;
  std::stringstream text(argv[4]);
  for (std::string item; std::getline(text, item, ',');) {
    const auto colon = item.find(':');
    stages.push_back({std::stod(item.substr(0, colon)), std::stoi(item.substr(colon + 1))});
  }
  const PeerRun run = RunPcl(fixed.positions, fixed.normals, moving.positions, moving.normals, start, stages,
                             std::stoi(argv[5]), 1);
  WriteTransformJson(argv[3], Similarity3::FromRigid(run.T));
  return 0;
}

}  // namespace
}  // namespace pectus
