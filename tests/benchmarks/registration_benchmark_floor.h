// pectus registration benchmark (issue 13), part "floor" (opt-in, --floor): what limits ICP's accuracy.
// On the speed pair, the first chest pairs of the "pairs" part (landmark start) and the bunny pairs (the
// disturbed published pose of seed 1), AlignIcp runs with one option changed at a time (the last sample
// fixed or every point, tighter tolerances, no extrapolation, no tangential rejection, a wider last gate,
// another loss, a lower scale floor), and PCL and Open3D with every point at pectus's last gate (gates 20,
// 5 mm and that gate). Printed per run: the error against the truth, iterations, the last sample's size
// and the pose's standard deviations. Included once, by registration_benchmark.cc.
#pragma once

#include <functional>
#include <map>

#include "registration/estimate_normals.h"
#include "registration/icp.h"
#include "registration/landmark_alignment.h"
#include "shape/io/mesh_io.h"
#include "shape/io/stanford_conf.h"
#include "tests/benchmarks/registration_benchmark_bunny.h"
#include "tests/benchmarks/registration_benchmark_peers.h"

namespace pectus {
namespace {

struct FloorCase {
  std::string name;
  ScanPair p;
  Rigid3 start;
};

std::vector<FloorCase> FloorCases(int chest_pairs) {
  std::vector<FloorCase> cases;
  {  // the speed part's pair and start
    std::mt19937_64 rng(20240901);
    const Rigid3 T_true = testing::RandomPose(&rng, 20.0, 100.0);
    FloorCase c{"speed pair", MakeScanPair(20240901), Rigid3::Identity()};
    MoveFrame(T_true, &c.p);
    const Eigen::Vector3d ctr = T_true * Eigen::Vector3d(c.p.moving.positions.colwise().mean().transpose());
    c.start = testing::RandomPose(&rng, 3.0, 10.0, ctr) * T_true;
    cases.push_back(std::move(c));
  }
  for (int k = 0; k < chest_pairs; ++k) {  // the pairs part's seeds, from the landmark pose
    const auto seed = static_cast<std::uint64_t>(1000 + k);
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    const double angle = 10.0 * u(rng), shift = 30.0 * u(rng);
    FloorCase c{"chest seed " + std::to_string(seed), MakeScanPair(seed), Rigid3::Identity()};
    const Eigen::Vector3d centre = c.p.moving.positions.colwise().mean().transpose();
    MoveFrame(testing::RandomPose(&rng, angle, shift, centre), &c.p);
    const LandmarkSet lf = Noisy(c.p.fixed_landmarks, 3.0, &rng);
    const LandmarkSet lm = Noisy(c.p.moving_landmarks, 3.0, &rng);
    c.start = AlignLandmarks(lm, lf).T_target_source.RigidPart();
    cases.push_back(std::move(c));
  }
  const fs::path dir = testing_support::BunnyDirectory();
  ReadOptions metres;
  metres.input_units = LengthUnit::kMetre;
  metres.warn_units = false;
  std::vector<ScanPose> poses = ReadStanfordConf(dir / "bun.conf");
  ScaleTranslations(1000.0, &poses);
  std::map<std::string, Rigid3> pose;
  for (const ScanPose& s : poses) pose[s.file] = s.T_common_scan;
  for (const auto& [f, m] : kBunnyPairs) {
    FloorCase c;
    c.name = f.substr(0, 6) + " <- " + m.substr(0, 6);
    c.p.fixed = ReadPointCloud(dir / f, metres);
    c.p.moving = ReadPointCloud(dir / m, metres);
    c.p.T_true = pose.at(f).inverse() * pose.at(m);
    std::mt19937_64 rng(1);
    const Eigen::Vector3d centre =
        c.p.T_true * Eigen::Vector3d(c.p.moving.positions.colwise().mean().transpose());
    c.start = testing::RandomPose(&rng, 5.0, 10.0, centre) * c.p.T_true;
    cases.push_back(std::move(c));
  }
  return cases;
}

json Floor(int chest_pairs, bool peers) {
  using Variant = std::pair<const char*, std::function<void(IcpOptions*)>>;
  const std::vector<Variant> variants = {
      {"defaults", [](IcpOptions*) {}},
      {"last sample fixed at 30000", [](IcpOptions* o) { o->target_pose_sd_fraction = 0.0; }},
      {"every point from the start", [](IcpOptions* o) { o->auto_level_points.back() = 0; }},
      {"tolerances / 10",
       [](IcpOptions* o) {
         o->rotation_tolerance_deg /= 10.0;
         o->translation_tolerance_mm /= 10.0;
         o->auto_max_iterations = 100;
       }},
      {"no Aitken extrapolation", [](IcpOptions* o) { o->extrapolate = false; }},
      {"no tangential rejection", [](IcpOptions* o) { o->max_tangential_spacings = 0.0; }},
      {"last gate 6 mm", [](IcpOptions* o) { o->final_max_distance_mm = 6.0; }},
      {"loss none", [](IcpOptions* o) { o->loss = RobustLoss::kNone; }},
      {"loss none, no tangential rejection",
       [](IcpOptions* o) {
         o->loss = RobustLoss::kNone;
         o->max_tangential_spacings = 0.0;
       }},
      {"robust scale floor 0.001 mm", [](IcpOptions* o) { o->min_robust_scale_mm = 0.001; }},
  };
  NormalOptions no;
  no.k = 12;
  no.orientation = NormalOrientation::kNone;
  json rows = json::array();
  for (const FloorCase& c : FloorCases(chest_pairs)) {
    const Points3 nt = EstimateNormals(c.p.fixed.positions, no).normals;
    const IcpTarget target(c.p.fixed.positions, nt);
    auto row = [&](const std::string& variant, const Rigid3& T) {
      const PoseError e = ErrorOf(T, c.p);
      return json{{"case", c.name},
                  {"variant", variant},
                  {"rotation_deg", e.rotation_deg},
                  {"translation_mm", e.translation_mm}};
    };
    for (const auto& [name, set] : variants) {
      IcpOptions o;
      set(&o);
      const IcpResult r = AlignIcp(target, c.p.moving.positions, Points3(), c.start, o);
      json j = row(name, r.T_target_source);
      j["success"] = r.success;
      j["iterations"] = r.iterations;
      j["last_sample_points"] = r.levels.back().source_points;
      j["rotation_sd_deg"] = r.rotation_sd_deg;
      j["translation_sd_mm"] = r.translation_sd_mm;
      rows.push_back(j);
    }
    if (peers) {
      const Points3 ns = EstimateNormals(c.p.moving.positions, no).normals;
      const std::vector<Stage> staged = {{20.0, 0}, {5.0, 0}, {3.0 * target.spacing_mm(), 0}};
      rows.push_back(
          row("PCL, every point at pectus's last gate",
              RunPcl(c.p.fixed.positions, nt, c.p.moving.positions, ns, c.start, staged, 30, 1).T));
      const fs::path dir = fs::temp_directory_path() / ("pectus_reg_floor_" + std::to_string(::getpid()));
      WriteOpen3dInputs(dir, c.p.fixed.positions, nt, c.p.moving.positions, ns, c.start);
      rows.push_back(row("Open3D, every point at pectus's last gate", RunOpen3d(dir, staged, 30, 1).T));
      std::error_code ec;
      fs::remove_all(dir, ec);
    }
    std::cerr << "floor: " << c.name << "\n";
  }
  return rows;
}

}  // namespace
}  // namespace pectus
