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
//   bunny   Stanford bunny sweep pairs from disturbed bun.conf poses: RMS distance to the published
//   placement.
//
// The chest scans come from the virtual scanner (pectus::datasets: merged sweeps of a population subject)
// when that library is built, else from the analytic surface of tests/registration/synthetic_chest.h.
//
//   registration_benchmark [--speed] [--pairs] [--bunny] [--trials N] [--repeat N] [--no-peers]
//   (no part named: all three)
#include <omp.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/registration/icp.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <random>
#include <string>
#include <vector>

#include "registration/icp.h"
#include "registration/normals.h"
#include "registration/pair_registration.h"
#include "registration/pose_error.h"
#include "registration/random_sample.h"
#include "shape/core/error.h"
#include "shape/io/mesh_io.h"
#include "shape/io/stanford_conf.h"
#include "shape/io/transform_io.h"
#include "tests/registration/synthetic_chest.h"
#ifdef PECTUS_HAVE_DATASETS
#include "datasets/synth.h"
#endif

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

// ---------------------------------------------------------------------------------------------------------
// Data: two scans of one chest, the moving one in a frame T_true^-1 away, with exact landmarks.

struct ScanPair {
  PointCloud fixed, moving;  // positions only
  LandmarkSet fixed_landmarks, moving_landmarks;
  Rigid3 T_true;  // T_fixed_moving
};

#ifdef PECTUS_HAVE_DATASETS
constexpr const char* kData =
    "virtual scanner (pectus::datasets): population subject, 5 sweeps each, 0.2 mm range noise, holes, "
    "0.3 % outliers; sweeps placed by their true poses; two scans with different seeds";

PointCloud MergedScan(const datasets::Scan& scan) {
  PointCloud out;
  for (const datasets::Sweep& s : scan.sweeps) {
    PointCloud c;
    c.positions = (s.cloud.positions * s.truth.T_scan_sweep.linear().transpose()).rowwise() +
                  s.truth.T_scan_sweep.translation().transpose();
    if (out.empty()) {
      out = c;
    } else {
      out.Append(c);
    }
  }
  return out;
}

ScanPair MakeScanPair(std::uint64_t seed) {
  datasets::ScanOptions scan;
  scan.noise_mm = 0.2;
  const datasets::SyntheticSubject subject = datasets::MakeSubject(datasets::SubjectOptions{}, seed, 0);
  const datasets::ScannedSubject a = datasets::ScanSubject(subject, scan, 0.0, 2 * seed);
  const datasets::ScannedSubject b = datasets::ScanSubject(subject, scan, 0.0, 2 * seed + 1);
  ScanPair p;
  p.T_true = Rigid3::Identity();
  p.fixed = MergedScan(a.scan);
  p.moving = MergedScan(b.scan);
  p.fixed_landmarks = a.true_landmarks;
  p.moving_landmarks = b.true_landmarks;
  return p;
}
#else
constexpr const char* kData =
    "analytic chest (tests/registration/synthetic_chest.h), 50k points per scan, 0.2 mm noise along the "
    "normal, overlapping parts of the surface";

ScanPair MakeScanPair(std::uint64_t seed) {
  ScanPair p;
  p.T_true = Rigid3::Identity();
  p.fixed = testing::SampleChest(50000, seed, 0.2, -1.3, 0.9);
  p.moving = testing::SampleChest(50000, seed + 1000003, 0.2, -0.9, 1.3);
  p.fixed.normals.resize(0, 3);
  p.moving.normals.resize(0, 3);
  const testing::ChestSurface s;
  const std::vector<std::tuple<std::string, double, double>> where = {{"notch", 0.0, 300.0},
                                                                      {"xiphoid", 0.0, 130.0},
                                                                      {"nipple_l", -0.6, 200.0},
                                                                      {"nipple_r", 0.6, 205.0},
                                                                      {"umbilicus", 0.05, 20.0}};
  for (const auto& [label, phi, h] : where) {
    p.fixed_landmarks.items.push_back({label, s.Point(phi, h), ""});
    p.moving_landmarks.items.push_back({label, s.Point(phi, h), ""});
  }
  return p;
}
#endif

// Moves the moving scan (and its landmarks) into a frame T_true^-1 away: T_fixed_moving = T_true.
void MoveFrame(const Rigid3& T_true, ScanPair* p) {
  p->T_true = T_true;
  TransformInPlace(Similarity3::FromRigid(T_true.inverse()), &p->moving);
  for (Landmark& l : p->moving_landmarks.items) l.position = T_true.inverse() * l.position;
}

LandmarkSet Noisy(LandmarkSet set, double sd_mm, std::mt19937_64* rng) {
  std::normal_distribution<double> g(0.0, sd_mm);
  for (Landmark& l : set.items) l.position += Eigen::Vector3d(g(*rng), g(*rng), g(*rng));
  return set;
}

PoseError ErrorOf(const Similarity3& estimate, const ScanPair& p) {
  return ComparePoses(estimate, Similarity3::FromRigid(p.T_true),
                      p.moving.positions.colwise().mean().transpose());
}
PoseError ErrorOf(const Rigid3& estimate, const ScanPair& p) {
  return ErrorOf(Similarity3::FromRigid(estimate), p);
}

json ErrorJson(const PoseError& e) {
  return {{"rotation_deg", e.rotation_deg}, {"translation_mm", e.translation_mm}};
}

// ---------------------------------------------------------------------------------------------------------
// Speed: pectus vs PCL vs Open3D on the same data, same normals, same start.

pcl::PointCloud<pcl::PointNormal>::Ptr ToPcl(const Points3& x, const Points3& n,
                                             const std::vector<std::uint32_t>* rows = nullptr) {
  auto cloud = std::make_shared<pcl::PointCloud<pcl::PointNormal>>();
  const std::size_t m = rows ? rows->size() : static_cast<std::size_t>(x.rows());
  cloud->resize(m);
  for (std::size_t k = 0; k < m; ++k) {
    const Eigen::Index i = rows ? (*rows)[k] : static_cast<Eigen::Index>(k);
    pcl::PointNormal& p = (*cloud)[k];
    p.x = static_cast<float>(x(i, 0));
    p.y = static_cast<float>(x(i, 1));
    p.z = static_cast<float>(x(i, 2));
    p.normal_x = static_cast<float>(n(i, 0));
    p.normal_y = static_cast<float>(n(i, 1));
    p.normal_z = static_cast<float>(n(i, 2));
  }
  return cloud;
}

struct Stage {
  double gate_mm;
  int points;  // 0: every point
};

std::string StagesText(const std::vector<Stage>& stages) {
  std::string s;
  for (const Stage& st : stages)
    s += (s.empty() ? "" : ",") + std::to_string(st.gate_mm) + ":" + std::to_string(st.points);
  return s;
}

// PCL, staged like pectus's levels (one stage = plain ICP). The source subsets are made before timing; the
// target's k-d tree is built once inside the timed region (PCL builds it lazily on the first align).
json RunPcl(const ScanPair& p, const Points3& nt, const Points3& ns, const Rigid3& start,
            const std::vector<Stage>& stages, int max_iterations, int repeat) {
  const auto target = ToPcl(p.fixed.positions, nt);
  std::vector<std::uint32_t> all(static_cast<std::size_t>(p.moving.size()));
  for (std::size_t i = 0; i < all.size(); ++i) all[i] = static_cast<std::uint32_t>(i);
  const std::vector<std::uint32_t> shuffled = RandomSample(all, all.size(), 1);
  std::vector<pcl::PointCloud<pcl::PointNormal>::Ptr> sources;
  for (const Stage& st : stages) {
    std::vector<std::uint32_t> rows(
        shuffled.begin(), shuffled.begin() + (st.points > 0 && st.points < static_cast<int>(all.size())
                                                  ? st.points
                                                  : static_cast<int>(all.size())));
    std::sort(rows.begin(), rows.end());
    sources.push_back(ToPcl(p.moving.positions, ns, &rows));
  }
  std::vector<double> times;
  Eigen::Matrix4f T = start.matrix().cast<float>();
  int iterations = 0;
  for (int k = 0; k < repeat; ++k) {
    T = start.matrix().cast<float>();
    iterations = 0;
    pcl::IterativeClosestPointWithNormals<pcl::PointNormal, pcl::PointNormal> icp;
    const auto t0 = Clock::now();
    icp.setInputTarget(target);
    for (std::size_t s = 0; s < stages.size(); ++s) {
      icp.setInputSource(sources[s]);
      icp.setMaxCorrespondenceDistance(stages[s].gate_mm);
      icp.setMaximumIterations(max_iterations);
      icp.setTransformationEpsilon(2e-3 * 2e-3);  // squared translation of an update, mm^2 (as pectus)
      icp.setTransformationRotationEpsilon(std::cos(1e-3 * M_PI / 180.0));  // cosine (as pectus)
      icp.setEuclideanFitnessEpsilon(1e-6);  // relative change of the MSE (as Open3D below)
      pcl::PointCloud<pcl::PointNormal> aligned;
      icp.align(aligned, T);
      T = icp.getFinalTransformation();
      iterations += icp.nr_iterations_;
    }
    times.push_back(Since(t0));
  }
  Rigid3 R = Rigid3::Identity();
  R.matrix() = T.cast<double>();
  R.linear() = Eigen::Quaterniond(R.linear()).normalized().toRotationMatrix();  // PCL works in float
  return {{"seconds_median", Median(times)},
          {"seconds_best", *std::min_element(times.begin(), times.end())},
          {"error", ErrorJson(ErrorOf(R, p))},
          {"iterations", iterations},
          {"stages", StagesText(stages)},
          {"threads", 1},
          {"method", "pcl::IterativeClosestPointWithNormals (point-to-plane LLS, float), " +
                         std::to_string(max_iterations) + " iterations max per stage"}};
}

json RunOpen3d(const fs::path& dir, const ScanPair& p, const std::vector<Stage>& stages, int max_iterations,
               int repeat) {
  const std::string script = std::string(PECTUS_SOURCE_DIR) + "/scripts/peers/open3d_icp.py";
  const fs::path out = dir / "open3d.json";
  const std::string cmd = "/usr/bin/python3 " + script + " " + (dir / "target.ply").string() + " " +
                          (dir / "source.ply").string() + " " + (dir / "init.json").string() + " --stages " +
                          StagesText(stages) + " --max-iterations " + std::to_string(max_iterations) +
                          " --repeat " + std::to_string(repeat) + " > " + out.string();
  if (std::system(cmd.c_str()) != 0) return {{"error", "command failed: " + cmd}};
  std::ifstream in(out);
  json o = json::parse(in);
  Rigid3 R = Rigid3::Identity();
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) R.matrix()(i, j) = o["T_target_source"][i][j].get<double>();
  return {{"seconds_median", o["seconds_median"]},
          {"seconds_best", o["seconds_best"]},
          {"error", ErrorJson(ErrorOf(R, p))},
          {"fitness", o["fitness"]},
          {"inlier_rmse_mm", o["inlier_rmse_mm"]},
          {"stages", StagesText(stages)},
          {"threads", omp_get_max_threads()},
          {"version", o["open3d_version"]},
          {"method", "open3d registration_icp, TransformationEstimationPointToPlane, " +
                         std::to_string(max_iterations) +
                         " iterations max per stage, relative fitness and "
                         "RMSE 1e-6; its target k-d tree is rebuilt inside every call"}};
}

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
                 {"normals_seconds_target", nt.seconds},
                 {"normals_seconds_source", ns.seconds},
                 {"normals",
                  "precomputed once with pectus EstimateNormals (k = 12) and given to every method; "
                  "not in any time below"}};

  // pectus: prepare the target (centre, k-d tree, spacing) and align, both timed; default options.
  std::vector<double> total, prepare;
  IcpResult r;
  for (int k = 0; k < repeat; ++k) {
    const auto t0 = Clock::now();
    const IcpTarget target(p.fixed.positions, nt.normals);
    prepare.push_back(Since(t0));
    r = AlignIcp(target, p.moving.positions, Points3(), start);
    total.push_back(Since(t0));
  }
  json levels = json::array();
  std::vector<Stage> stages;
  for (const auto& l : r.levels) {
    levels.push_back({{"points", l.source_points},
                      {"gate_mm", l.max_distance_mm},
                      {"iterations", l.iterations},
                      {"tree_searches", l.searches}});
    stages.push_back(
        {l.max_distance_mm, l.source_points < p.moving.size() ? static_cast<int>(l.source_points) : 0});
  }
  out["pectus"] = {{"seconds_median", Median(total)},
                   {"seconds_best", *std::min_element(total.begin(), total.end())},
                   {"seconds_prepare_target_median", Median(prepare)},
                   {"error", ErrorJson(ErrorOf(r.T_target_source, p))},
                   {"success", r.success},
                   {"iterations", r.iterations},
                   {"levels", levels},
                   {"rms_mm", r.rms_mm},
                   {"runs", repeat},
                   {"threads", omp_get_max_threads()},
                   {"timed", "IcpTarget (centring, k-d tree, spacing) + AlignIcp"},
                   {"method",
                    "point-to-plane, Cauchy loss, nested random levels, certified correspondence reuse "
                    "(defaults)"}};
  if (!peers) return out;

  const std::vector<Stage> plain = {{15.0, 0}};
  const int peer_repeat = std::max(1, std::min(repeat, 3));
  out["pcl_plain"] = RunPcl(p, nt.normals, ns.normals, start, plain, 50, peer_repeat);
  out["pcl_staged"] = RunPcl(p, nt.normals, ns.normals, start, stages, 30, peer_repeat);

  const fs::path dir = fs::temp_directory_path() / ("pectus_reg_bench_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  PointCloud t = p.fixed, s = p.moving;
  t.normals = nt.normals;
  s.normals = ns.normals;
  WritePointCloud(dir / "target.ply", t);
  WritePointCloud(dir / "source.ply", s);
  WriteTransformJson(dir / "init.json", Similarity3::FromRigid(start));
  out["open3d_plain"] = RunOpen3d(dir, p, plain, 50, peer_repeat);
  out["open3d_staged"] = RunOpen3d(dir, p, stages, 30, peer_repeat);
  std::error_code ec;
  fs::remove_all(dir, ec);

  const double mine = Median(total);
  for (const char* peer : {"pcl_plain", "pcl_staged", "open3d_plain", "open3d_staged"}) {
    if (out[peer].contains("seconds_median")) {
      out["ratios"][std::string(peer) + "_over_pectus_time"] =
          out[peer]["seconds_median"].get<double>() / mine;
    }
  }
  return out;
}

// ---------------------------------------------------------------------------------------------------------
// Pairs: seeded trials with landmarks (the acceptance), and apart ICP alone from the same start.

json Pairs(int trials) {
  json out;
  struct Tally {
    int within = 0, reported_failure = 0, silent_bad = 0;
    std::vector<double> rot, trans, seconds;
    json bad = json::array();
  };
  Tally with, without;
  std::int64_t points = 0;
  for (int k = 0; k < trials; ++k) {
    const auto seed = static_cast<std::uint64_t>(1000 + k);
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    const double angle = 10.0 * u(rng), shift = 30.0 * u(rng);
    // The moving scan's frame: the fixed frame turned by `angle` about the chest and shifted by `shift`.
    ScanPair p = MakeScanPair(seed);
    const Eigen::Vector3d centre = p.moving.positions.colwise().mean().transpose();
    MoveFrame(testing::RandomPose(&rng, angle, shift, centre), &p);
    points += p.fixed.size() + p.moving.size();
    const LandmarkSet lf = Noisy(p.fixed_landmarks, 3.0, &rng);
    const LandmarkSet lm = Noisy(p.moving_landmarks, 3.0, &rng);
    for (const bool landmarks : {true, false}) {
      Tally& t = landmarks ? with : without;
      const auto t0 = Clock::now();
      const PairRegistrationResult r = RegisterPair(p.fixed, p.moving, landmarks ? &lf : nullptr,
                                                    landmarks ? &lm : nullptr, Similarity3{}, {});
      t.seconds.push_back(Since(t0));
      const PoseError e = ErrorOf(r.T_target_source, p);
      const bool good = e.rotation_deg <= 0.05 && e.translation_mm <= 0.1;
      t.rot.push_back(e.rotation_deg);
      t.trans.push_back(e.translation_mm);
      t.within += r.success && good;
      t.reported_failure += !r.success;
      if (r.success != good) {
        t.silent_bad += r.success && !good;
        t.bad.push_back(
            {{"seed", seed}, {"success", r.success}, {"error", ErrorJson(e)}, {"message", r.message}});
      }
    }
    std::cerr << "\rpairs: " << k + 1 << " / " << trials << std::flush;
  }
  std::cerr << "\n";
  auto summary = [&](Tally& t, bool landmarks) {
    std::sort(t.rot.begin(), t.rot.end());
    std::sort(t.trans.begin(), t.trans.end());
    auto at = [](const std::vector<double>& v, double q) {
      return v[std::min(v.size() - 1, static_cast<std::size_t>(q * static_cast<double>(v.size())))];
    };
    return json{
        {"trials", trials},
        {"within_tolerance", t.within},
        {"within_fraction", static_cast<double>(t.within) / trials},
        {"reported_failure", t.reported_failure},
        {"silent_bad_fits", t.silent_bad},
        {"mismatches", t.bad},
        {"rotation_deg_median", at(t.rot, 0.5)},
        {"rotation_deg_p99", at(t.rot, 0.99)},
        {"rotation_deg_max", t.rot.back()},
        {"translation_mm_median", at(t.trans, 0.5)},
        {"translation_mm_p99", at(t.trans, 0.99)},
        {"translation_mm_max", t.trans.back()},
        {"seconds_median_per_pair", Median(t.seconds)},
        {"start", landmarks ? "landmark alignment (Umeyama, 3 mm noise per axis on both sets), then ICP"
                            : "ICP alone from the identity (the full frame offset is the start error)"}};
  };
  out["data"] = kData;
  out["mean_points_per_scan"] = static_cast<double>(points) / (2.0 * trials);
  out["setup"] =
      "frame offset uniform in [0, 10] deg about the chest centroid and [0, 30] mm; tolerance: "
      "rotation <= 0.05 deg and translation <= 0.1 mm at the moving scan's centroid";
  out["with_landmarks"] = summary(with, true);
  out["icp_only"] = summary(without, false);
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
  const std::vector<std::pair<std::string, std::string>> pairs = {{"bun000.ply", "bun045.ply"},
                                                                  {"bun270.ply", "bun315.ply"},
                                                                  {"bun000.ply", "bun315.ply"},
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
      const PairRegistrationResult r =
          RegisterPair(fixed, moving, nullptr, nullptr, Similarity3::FromRigid(start));
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
  int trials = 200, repeat = 5;
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
    } else if (a == "--no-peers") {
      peers = false;
    } else if (a == "--trials") {
      trials = value();
    } else if (a == "--repeat") {
      repeat = value();
    } else {
      std::cerr << "usage: registration_benchmark [--speed] [--pairs] [--bunny] [--trials N] [--repeat N]"
                   " [--no-peers]\n";
      return 2;
    }
  }
  if (!speed && !pairs && !bunny) speed = pairs = bunny = true;
  json out;
  out["machine_threads"] = omp_get_max_threads();
  if (speed) out["speed"] = Speed(std::max(1, repeat), peers);
  if (bunny) out["bunny"] = Bunny(5);
  if (pairs) out["pairs"] = Pairs(std::max(1, trials));
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
