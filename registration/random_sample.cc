#include "registration/random_sample.h"

#include <algorithm>
#include <utility>

namespace pectus {
std::uint64_t SplitMix64(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

std::vector<std::uint32_t> RandomSample(const std::vector<std::uint32_t>& rows, std::size_t count,
                                        std::uint64_t seed) {
  std::vector<std::uint32_t> out = rows;
  const std::size_t n = out.size();
  const std::size_t m = std::min(count, n);
  std::uint64_t state = seed;
  for (std::size_t i = 0; i < m && i + 1 < n; ++i) {
    // The generator: SplitMix64 of a counter stepped by its constant. Lemire's multiply-shift maps 32
    // random bits to [0, n - i) (rows are 32-bit, so n - i < 2^32).
    const std::uint64_t bits = SplitMix64(state) >> 32;
    state += 0x9e3779b97f4a7c15ULL;
    const std::size_t j = i + static_cast<std::size_t>((bits * static_cast<std::uint64_t>(n - i)) >> 32);
    std::swap(out[i], out[j]);
  }
  out.resize(m);
  return out;
}

}  // namespace pectus
