// pectus registration benchmark (issue 4). Prints one JSON object with three parts:
//
//   speed   pectus ICP against PCL (IterativeClosestPointWithNormals) and Open3D (registration_icp,
//           point-to-plane, run by scripts/peers/open3d_icp.py with /usr/bin/python3) on the same two
//           ~100k-point chest scans, same normals (precomputed once, timed apart), same start pose: time,
//           rotation and translation error, and the ratios.
//   pairs   seeded trials of synthetic chest pairs (0.2 mm surface noise, start error up to 10 degrees and
//           30 mm, landmark noise 3 mm per axis): the fraction within 0.05 degrees and 0.1 mm, and whether
//           every other trial reported failure.
//   bunny   Stanford bunny sweep pairs from disturbed bun.conf poses: RMS distance to the published
//           placement.
//
//   registration_benchmark [--speed] [--pairs] [--bunny] [--trials N] [--points N] [--repeat N] [--no-peers]
//   (no part named: all three)
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/registration/icp.h>

#include <omp.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <optional>
#include <random>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

#include "registration/icp.h"
#include "registration/normals.h"
#include "registration/pair_registration.h"
#include "registration/pose_error.h"
#include "shape/core/error.h"
#include "shape/io/mesh_io.h"
#include "shape/io/stanford_conf.h"
#include "shape/io/transform_io.h"
#include "tests/registration/synthetic_chest.h"

namespace pectus {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;
using nlohmann::json;

double Since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

double Median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0 : v[v.size() / 2];
}

// The moving scan of a pair, a second sampling of the chest seen from the other side, in its own frame.
struct ChestPair {
  PointCloud fixed, moving;
  Rigid3 T_true;  // T_fixed_moving
};

ChestPair MakeChestPair(std::uint64_t seed, int points, double angle_deg, double shift_mm) {
  ChestPair p;
  p.fixed = testing::SampleChest(points, seed, 0.2, -1.3, 0.9);
  std::mt19937_64 rng(seed * 7919 + 1);
  const Eigen::Vector3d centre(0, 100, 160);
  p.T_true = testing::RandomPose(&rng, angle_deg, shift_mm, centre);
  p.moving = testing::Transformed(testing::SampleChest(points, seed + 1000003, 0.2, -0.9, 1.3), p.T_true.inverse());
  p.fixed.normals.resize(0, 3);
  p.moving.normals.resize(0, 3);
  return p;
}

PoseError ErrorOf(const Similarity3& estimate, const ChestPair& p) {
  return ComparePoses(estimate, Similarity3::FromRigid(p.T_true), p.moving.positions.colwise().mean().transpose());
}

json ErrorJson(const PoseError& e) { return {{"rotation_deg", e.rotation_deg}, {"translation_mm", e.translation_mm}}; }

// ---------------------------------------------------------------------------------------------------------
// Speed: pectus vs PCL vs Open3D on the same data.

pcl::PointCloud<pcl::PointNormal>::Ptr ToPcl(const Points3& x, const Points3& n) {
  auto cloud = std::make_shared<pcl::PointCloud<pcl::PointNormal>>();
  cloud->resize(static_cast<std::size_t>(x.rows()));
  for (Eigen::Index i = 0; i < x.rows(); ++i) {
    pcl::PointNormal& p = (*cloud)[static_cast<std::size_t>(i)];
    p.x = static_cast<float>(x(i, 0));
    p.y = static_cast<float>(x(i, 1));
    p.z = static_cast<float>(x(i, 2));
    p.normal_x = static_cast<float>(n(i, 0));
    p.normal_y = static_cast<float>(n(i, 1));
    p.normal_z = static_cast<float>(n(i, 2));
  }
  return cloud;
}

json Speed(int points, int repeat, bool peers, double max_distance_mm) {
  const ChestPair p = MakeChestPair(20240901, points, 8.0, 25.0);
  std::mt19937_64 rng(99);
  const Eigen::Vector3d c = p.T_true * Eigen::Vector3d(p.moving.positions.colwise().mean().transpose());
  const Rigid3 start = testing::RandomPose(&rng, 3.0, 10.0, c) * p.T_true;

  // Normals, once, for everybody (pectus's EstimateNormals, k = 12); timed on their own.
  NormalOptions no;
  no.k = 12;
  no.orientation = NormalOrientation::kNone;
  const NormalResult nt = EstimateNormals(p.fixed.positions, no);
  const NormalResult ns = EstimateNormals(p.moving.positions, no);

  json out;
  out["data"] = {{"target_points", p.fixed.size()},
                 {"source_points", p.moving.size()},
                 {"surface_noise_mm", 0.2},
                 {"start_error", ErrorJson(ErrorOf(Similarity3::FromRigid(start), p))},
                 {"normals_seconds_target", nt.seconds},
                 {"normals_seconds_source", ns.seconds},
                 {"normals", "precomputed once with pectus EstimateNormals (k = 12) and given to every method"}};

  // pectus: prepare the target (centre, k-d tree) and align, both timed; default options.
  std::vector<double> total, prepare;
  IcpResult r;
  for (int k = 0; k < repeat; ++k) {
    const auto t0 = Clock::now();
    const IcpTarget target(p.fixed.positions, nt.normals);
    const double t_prepare = Since(t0);
    r = AlignIcp(target, p.moving.positions, Points3(), start);
    total.push_back(Since(t0));
    prepare.push_back(t_prepare);
  }
  const PoseError pe = ErrorOf(Similarity3::FromRigid(r.T_target_source), p);
  json levels = json::array();
  for (const auto& l : r.levels) levels.push_back({{"points", l.source_points}, {"iterations", l.iterations}});
  out["pectus"] = {{"seconds_median", Median(total)},
                   {"seconds_best", *std::min_element(total.begin(), total.end())},
                   {"seconds_prepare_target_median", Median(prepare)},
                   {"error", ErrorJson(pe)},
                   {"success", r.success},
                   {"iterations", r.iterations},
                   {"levels", levels},
                   {"rms_mm", r.rms_mm},
                   {"runs", repeat},
                   {"method", "point-to-plane, Cauchy loss, coarse-to-fine voxel levels (defaults)"}};
  if (!peers) return out;

  // PCL: IterativeClosestPointWithNormals (point-to-plane LLS), every point, one gate.
  {
    auto target = ToPcl(p.fixed.positions, nt.normals);
    auto source = ToPcl(p.moving.positions, ns.normals);
    std::vector<double> times;
    Eigen::Matrix4d T = Eigen::Matrix4d::Identity();
    bool converged = false;
    const int runs = std::max(1, std::min(repeat, 2));
    for (int k = 0; k < runs; ++k) {
      pcl::IterativeClosestPointWithNormals<pcl::PointNormal, pcl::PointNormal> icp;
      icp.setMaxCorrespondenceDistance(max_distance_mm);
      icp.setMaximumIterations(50);
      icp.setTransformationEpsilon(1e-10);
      icp.setEuclideanFitnessEpsilon(1e-10);
      pcl::PointCloud<pcl::PointNormal> aligned;
      const auto t0 = Clock::now();
      icp.setInputTarget(target);
      icp.setInputSource(source);
      icp.align(aligned, start.matrix().cast<float>());
      times.push_back(Since(t0));
      T = icp.getFinalTransformation().cast<double>();
      converged = icp.hasConverged();
    }
    Rigid3 R = Rigid3::Identity();
    R.matrix() = T;
    // PCL works in float: re-orthonormalise before comparing.
    R.linear() = Eigen::Quaterniond(R.linear()).normalized().toRotationMatrix();
    const PoseError e = ErrorOf(Similarity3::FromRigid(R), p);
    out["pcl"] = {{"seconds_median", Median(times)},
                  {"error", ErrorJson(e)},
                  {"converged", converged},
                  {"runs", runs},
                  {"method", "pcl::IterativeClosestPointWithNormals, gate " + std::to_string(max_distance_mm) +
                                 " mm, 50 iterations max"}};
    out["ratios"]["pcl_over_pectus_time"] = Median(times) / Median(total);
  }

  // Open3D: the same data through PLY files, timed inside Python around registration_icp only.
  {
    const fs::path dir = fs::temp_directory_path() / ("pectus_reg_bench_" + std::to_string(::getpid()));
    fs::create_directories(dir);
    PointCloud t = p.fixed, s = p.moving;
    t.normals = nt.normals;
    s.normals = ns.normals;
    WritePointCloud(dir / "target.ply", t);
    WritePointCloud(dir / "source.ply", s);
    WriteTransformJson(dir / "init.json", Similarity3::FromRigid(start));
    const std::string script = std::string(PECTUS_SOURCE_DIR) + "/scripts/peers/open3d_icp.py";
    const std::string cmd = "/usr/bin/python3 " + script + " " + (dir / "target.ply").string() + " " +
                            (dir / "source.ply").string() + " " + (dir / "init.json").string() +
                            " --max-distance " + std::to_string(max_distance_mm) + " --max-iterations 50 --repeat " +
                            std::to_string(repeat) + " > " + (dir / "open3d.json").string();
    const int rc = std::system(cmd.c_str());
    if (rc != 0) {
      out["open3d"] = {{"error", "command failed: " + cmd}};
    } else {
      std::ifstream in(dir / "open3d.json");
      json o = json::parse(in);
      Eigen::Matrix4d T;
      for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) T(i, j) = o["T_target_source"][i][j].get<double>();
      Rigid3 R = Rigid3::Identity();
      R.matrix() = T;
      const PoseError e = ErrorOf(Similarity3::FromRigid(R), p);
      out["open3d"] = {{"seconds_best", o["seconds"]},
                       {"error", ErrorJson(e)},
                       {"fitness", o["fitness"]},
                       {"inlier_rmse_mm", o["inlier_rmse_mm"]},
                       {"version", o["open3d_version"]},
                       {"method", "open3d registration_icp, TransformationEstimationPointToPlane, gate " +
                                      std::to_string(max_distance_mm) + " mm, 50 iterations max"}};
      out["ratios"]["open3d_over_pectus_time"] =
          o["seconds"].get<double>() / *std::min_element(total.begin(), total.end());
    }
    std::error_code ec;
    fs::remove_all(dir, ec);
  }
  return out;
}

// ---------------------------------------------------------------------------------------------------------
// Pairs: seeded trials with landmarks (and, apart, without).

LandmarkSet ChestLandmarks(const Rigid3& T, double noise_mm, std::mt19937_64* rng) {
  const testing::ChestSurface s;
  const std::vector<std::tuple<std::string, double, double>> where = {
      {"notch", 0.0, 300.0}, {"xiphoid", 0.0, 130.0}, {"nipple_l", -0.6, 200.0}, {"nipple_r", 0.6, 205.0},
      {"umbilicus", 0.05, 20.0}};
  std::normal_distribution<double> g(0.0, noise_mm);
  LandmarkSet set;
  for (const auto& [label, phi, h] : where) {
    set.items.push_back({label, T * s.Point(phi, h) + Eigen::Vector3d(g(*rng), g(*rng), g(*rng)), ""});
  }
  return set;
}

json Pairs(int trials, int points) {
  json out;
  for (const bool landmarks : {true, false}) {
    int within = 0, reported_failure = 0, silent_bad = 0;
    std::vector<double> rot, trans, seconds;
    json worst = json::array();
    for (int k = 0; k < trials; ++k) {
      const auto seed = static_cast<std::uint64_t>(1000 + k);
      std::mt19937_64 rng(seed);
      std::uniform_real_distribution<double> u(0.0, 1.0);
      const double angle = 10.0 * u(rng), shift = 30.0 * u(rng);
      const ChestPair p = MakeChestPair(seed, points, angle, shift);
      std::optional<LandmarkSet> lf, lm;
      if (landmarks) {
        lf = ChestLandmarks(Rigid3::Identity(), 3.0, &rng);
        lm = ChestLandmarks(p.T_true.inverse(), 3.0, &rng);
      }
      const auto t0 = Clock::now();
      const PairRegistrationResult r =
          RegisterPair(p.fixed, p.moving, lf ? &*lf : nullptr, lm ? &*lm : nullptr, Similarity3{}, {});
      seconds.push_back(Since(t0));
      const PoseError e = ErrorOf(r.T_target_source, p);
      const bool good = e.rotation_deg <= 0.05 && e.translation_mm <= 0.1;
      rot.push_back(e.rotation_deg);
      trans.push_back(e.translation_mm);
      if (r.success && good) ++within;
      if (!r.success) ++reported_failure;
      if (r.success && !good) {
        ++silent_bad;
        worst.push_back({{"seed", seed}, {"error", ErrorJson(e)}, {"message", r.message}});
      }
    }
    std::sort(rot.begin(), rot.end());
    std::sort(trans.begin(), trans.end());
    const auto at = [&](const std::vector<double>& v, double q) {
      return v[std::min(v.size() - 1, static_cast<std::size_t>(q * static_cast<double>(v.size())))];
    };
    out[landmarks ? "with_landmarks" : "icp_only_from_start"] = {
        {"trials", trials},
        {"points_per_scan", points},
        {"within_tolerance", within},
        {"within_fraction", static_cast<double>(within) / trials},
        {"reported_failure", reported_failure},
        {"silent_bad_fits", silent_bad},
        {"silent_bad_examples", worst},
        {"rotation_deg_median", at(rot, 0.5)},
        {"rotation_deg_p99", at(rot, 0.99)},
        {"rotation_deg_max", rot.back()},
        {"translation_mm_median", at(trans, 0.5)},
        {"translation_mm_p99", at(trans, 0.99)},
        {"translation_mm_max", trans.back()},
        {"seconds_median_per_pair", Median(seconds)},
        {"tolerance", "rotation <= 0.05 deg and translation <= 0.1 mm (at the moving scan's centroid)"},
        {"setup", std::string("start error uniform up to 10 deg and 30 mm; surface noise 0.2 mm; ") +
                      (landmarks ? "5 landmarks with 3 mm Gaussian noise per axis on each scan"
                                 : "no landmarks: ICP from the start pose")}};
  }
  return out;
}

// ---------------------------------------------------------------------------------------------------------
// Bunny: real sweeps, published placement as the answer.

json Bunny(int seeds) {
  const fs::path dir = fs::path(PECTUS_SHARED_DIR) / "datasets" / "stanford_bunny";
  ReadOptions metres;
  metres.input_units = LengthUnit::kMetre;
  metres.warn_units = false;
  std::vector<ScanPose> poses = ReadStanfordConf(dir / "bun.conf");
  ScaleTranslations(1000.0, &poses);
  auto pose = [&](const std::string& file) {
    for (const ScanPose& p : poses)
      if (p.file == file) return p.T_common_scan;
    ThrowBadInput((dir / "bun.conf").string(), "no pose for " + file);
  };
  json out = json::array();
  const std::vector<std::pair<std::string, std::string>> pairs = {
      {"bun000.ply", "bun045.ply"}, {"bun270.ply", "bun315.ply"}, {"bun000.ply", "bun315.ply"},
      {"bun045.ply", "bun090.ply"}};
  for (const auto& [fixed_name, moving_name] : pairs) {
    const PointCloud fixed = ReadPointCloud(dir / fixed_name, metres);
    const PointCloud moving = ReadPointCloud(dir / moving_name, metres);
    const Rigid3 published = pose(fixed_name).inverse() * pose(moving_name);
    const Eigen::Vector3d centre = published * Eigen::Vector3d(moving.positions.colwise().mean().transpose());
    std::vector<double> rms, seconds;
    int success = 0;
    for (int s = 1; s <= seeds; ++s) {
      std::mt19937_64 rng(static_cast<std::uint64_t>(s));
      const Rigid3 start = testing::RandomPose(&rng, 5.0, 10.0, centre) * published;
      const auto t0 = Clock::now();
      const PairRegistrationResult r = RegisterPair(fixed, moving, nullptr, nullptr, Similarity3::FromRigid(start));
      seconds.push_back(Since(t0));
      success += r.success;
      rms.push_back(RmsDisplacement(moving.positions, r.T_target_source, Similarity3::FromRigid(published)));
    }
    out.push_back({{"fixed", fixed_name},
                   {"moving", moving_name},
                   {"starts", seeds},
                   {"start", "published pose disturbed by 5 deg about the scan's centre and 10 mm"},
                   {"success", success},
                   {"rms_to_published_mm_median", Median(rms)},
                   {"rms_to_published_mm_max", *std::max_element(rms.begin(), rms.end())},
                   {"seconds_median", Median(seconds)},
                   {"note", "seconds include estimating the fixed scan's normals"}});
  }
  return out;
}

int Main(int argc, char** argv) {
  bool speed = false, pairs = false, bunny = false, peers = true;
  int trials = 200, points = 100000, pair_points = 50000, repeat = 5;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&]() {
      if (i + 1 >= argc) throw std::runtime_error(a + " needs a value");
      return std::stoi(argv[++i]);
    };
    if (a == "--speed") speed = true;
    else if (a == "--pairs") pairs = true;
    else if (a == "--bunny") bunny = true;
    else if (a == "--no-peers") peers = false;
    else if (a == "--trials") trials = value();
    else if (a == "--points") points = value();
    else if (a == "--pair-points") pair_points = value();
    else if (a == "--repeat") repeat = value();
    else {
      std::cerr << "usage: registration_benchmark [--speed] [--pairs] [--bunny] [--trials N] [--points N]"
                   " [--pair-points N] [--repeat N] [--no-peers]\n";
      return 2;
    }
  }
  if (!speed && !pairs && !bunny) speed = pairs = bunny = true;
  json out;
  out["machine_threads"] = omp_get_max_threads();
  if (speed) out["speed"] = Speed(points, repeat, peers, 15.0);
  if (bunny) out["bunny"] = Bunny(5);
  if (pairs) out["pairs"] = Pairs(trials, pair_points);
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
