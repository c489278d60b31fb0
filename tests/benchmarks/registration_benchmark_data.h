// pectus registration benchmark (issue 4): shared helpers (clock, CPU time, machine, medians) and the
// chest scan pairs with their known transform. Included once, by registration_benchmark.cc.
#pragma once

#include <time.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <random>
#include <string>
#include <tuple>
#include <vector>

#include "registration/pose_error.h"
#include "shape/core/geometry.h"
#include "shape/core/landmarks.h"
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

// CPU seconds of this process so far, all threads.
double CpuSeconds() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

// The first line of a file, or "" (for /proc/loadavg).
std::string FirstLine(const std::string& path) {
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);
  return line;
}

std::string CpuModel() {
  std::ifstream in("/proc/cpuinfo");
  for (std::string line; std::getline(in, line);) {
    if (line.rfind("model name", 0) == 0) return line.substr(line.find(':') + 2);
  }
  return "unknown";
}

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
  p.fixed_landmarks = testing::ChestLandmarks();
  p.moving_landmarks = testing::ChestLandmarks();
  return p;
}
#endif

// Moves the moving scan (and its landmarks) into a frame T_true^-1 away: T_fixed_moving = T_true.
void MoveFrame(const Rigid3& T_true, ScanPair* p) {
  p->T_true = T_true;
  TransformInPlace(Similarity3::FromRigid(T_true.inverse()), &p->moving);
  p->moving_landmarks = p->moving_landmarks.Transformed(Similarity3::FromRigid(T_true.inverse()));
}

LandmarkSet Noisy(LandmarkSet set, double sd_mm, std::mt19937_64* rng) {
  std::normal_distribution<double> g(0.0, sd_mm);
  for (Landmark& l : set.items) l.position += Eigen::Vector3d(g(*rng), g(*rng), g(*rng));
  return set;
}

// The benchmark's chest pair of `seed` (the "pairs" part's trial seed - 1000): the moving scan's frame is
// the fixed one turned by up to 10 degrees about the chest and shifted by up to 30 mm, and both scans'
// landmarks carry 3 mm of noise (into `fixed_landmarks`, `moving_landmarks`; the pair keeps the exact ones).
struct NoisyChestPair {
  ScanPair pair;
  LandmarkSet fixed_landmarks, moving_landmarks;
};
NoisyChestPair MakeNoisyChestPair(std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const double angle = 10.0 * u(rng), shift = 30.0 * u(rng);
  NoisyChestPair c{MakeScanPair(seed), {}, {}};
  const Eigen::Vector3d centre = c.pair.moving.positions.colwise().mean().transpose();
  MoveFrame(testing::RandomPose(&rng, angle, shift, centre), &c.pair);
  c.fixed_landmarks = Noisy(c.pair.fixed_landmarks, 3.0, &rng);
  c.moving_landmarks = Noisy(c.pair.moving_landmarks, 3.0, &rng);
  return c;
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

}  // namespace
}  // namespace pectus
