// pectus: summary figures of a sample of numbers (a benchmark's or an evaluation's errors).
#pragma once

#include <algorithm>
#include <cmath>
#include <numeric>
#include <utility>
#include <vector>

namespace pectus {

/// The q-quantile of `values` by linear interpolation between order statistics (q in [0, 1]; 0.5 is the
/// median, 0.95 the 95th percentile: the value at position q (n - 1) of the sorted values, as numpy's
/// default). 0 for an empty sample.
inline std::vector<double> Quantiles(std::vector<double> values, const std::vector<double>& qs);
inline double Quantile(std::vector<double> values, double q) { return Quantiles(std::move(values), {q})[0]; }

/// Quantile() at each of `qs` (ascending), in O(#values) per quantile by selection instead of a sort.
inline std::vector<double> Quantiles(std::vector<double> values, const std::vector<double>& qs) {
  std::vector<double> out(qs.size(), 0.0);
  if (values.empty()) return out;
  const std::size_t n = values.size();
  std::size_t from = 0;  // values[from, n) are unsorted, and no smaller than any before them
  for (std::size_t i = 0; i < qs.size(); ++i) {
    const double at = std::clamp(qs[i], 0.0, 1.0) * static_cast<double>(n - 1);
    const auto lo = static_cast<std::size_t>(std::floor(at));
    if (lo >= from) {
      std::nth_element(values.begin() + static_cast<std::ptrdiff_t>(from),
                       values.begin() + static_cast<std::ptrdiff_t>(lo), values.end());
      from = lo + 1;
    }
    const double next =
        lo + 1 < n ? *std::min_element(values.begin() + static_cast<std::ptrdiff_t>(lo + 1), values.end())
                   : values[lo];
    out[i] = values[lo] + (at - static_cast<double>(lo)) * (next - values[lo]);
  }
  return out;
}

/// The arithmetic mean of `values`; 0 for an empty sample.
inline double Mean(const std::vector<double>& values) {
  return values.empty()
             ? 0.0
             : std::accumulate(values.begin(), values.end(), 0.0) / static_cast<double>(values.size());
}

/// The largest of `values`; 0 for an empty sample.
inline double Max(const std::vector<double>& values) {
  return values.empty() ? 0.0 : *std::max_element(values.begin(), values.end());
}

}  // namespace pectus
