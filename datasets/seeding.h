// pectus datasets: derived random seeds, so that every subject and sweep has its own generator and the
// output does not depend on the number of threads or on the order of work.
#pragma once

#include <cstdint>

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

}  // namespace pectus::datasets
