// pectus datasets: derived random seeds, so that every subject and sweep has its own generator and the
// output does not depend on the number of threads or on the order of work.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <random>

namespace pectus::datasets {

/// SplitMix64 finaliser: a well-mixed 64-bit function of x.
inline std::uint64_t Mix64(std::uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

/// What a derived seed is for, so that two uses of the same index never share a stream.
enum class SeedStream : std::uint64_t {
  kSubject = 1,  ///< a subject's shape (latent factors, detail)
  kScan = 2,     ///< a subject's scan (holes, landmark noise, pose)
  kSweep = 3,    ///< one sweep of a scan
  kPair = 4,     ///< the second scan of a pair
};

/// The seed of item `index` of `stream` under `seed`.
inline std::uint64_t DeriveSeed(std::uint64_t seed, SeedStream stream, std::uint64_t index) {
  return Mix64(Mix64(seed ^ Mix64(static_cast<std::uint64_t>(stream))) + index);
}

/// A direction drawn uniformly on the unit sphere (a normalised standard normal 3-vector).
inline Eigen::Vector3d RandomUnit(std::mt19937_64* rng) {
  std::normal_distribution<double> normal(0.0, 1.0);
  Eigen::Vector3d a;
  do {
    a = Eigen::Vector3d(normal(*rng), normal(*rng), normal(*rng));
  } while (a.norm() < 1e-6);
  return a.normalized();
}

}  // namespace pectus::datasets
