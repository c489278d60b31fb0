// pectus: a deterministic uniform random sample of point rows, the sampling step of coarse-to-fine ICP.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace pectus {

/// SplitMix64's output for `x` (Steele, Lea and Flood 2014): a well-mixed 64-bit hash; a counter stepped
/// by 0x9e3779b97f4a7c15 through it is the SplitMix64 generator.
std::uint64_t SplitMix64(std::uint64_t x);

/// The first `count` rows of a deterministic random permutation of `rows` (a partial Fisher-Yates
/// shuffle driven by SplitMix64, so the same seed gives the same sample on every platform). Every prefix
/// of the result is itself a uniform random sample, so nested coarse-to-fine levels take prefixes of one
/// call. Unlike a voxel grid, a random sample keeps the proportions of the input: scattered clutter is not
/// over-represented at coarse levels (Rusinkiewicz and Levoy 2001, "Efficient variants of the ICP
/// algorithm", Sec. 3).
/// @param[in] rows   candidate rows (e.g. of a #points by 3 matrix)
/// @param[in] count  rows wanted; all of them (shuffled) when count >= rows.size()
/// @param[in] seed   any value; the sample is a function of (rows, count, seed)
std::vector<std::uint32_t> RandomSample(const std::vector<std::uint32_t>& rows, std::size_t count,
                                        std::uint64_t seed = 0x9e3779b97f4a7c15ULL);

}  // namespace pectus
