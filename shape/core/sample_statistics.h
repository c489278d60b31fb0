// pectus: summary figures of a sample of numbers (a benchmark's or an evaluation's errors).
#pragma once

#include <algorithm>
#include <cmath>
#include <numeric>
#include <vector>

namespace pectus {

/// The q-quantile of `values` by linear interpolation between order statistics (q in [0, 1]; 0.5 is the
/// median, 0.95 the 95th percentile: the value at position q (n - 1) of the sorted values, as numpy's
/// default). 0 for an empty sample.
inline double Quantile(std::vector<double> values, double q) {
  if (values.empty()) return 0.0;
  std::sort(values.begin(), values.end());
  const double at = std::clamp(q, 0.0, 1.0) * static_cast<double>(values.size() - 1);
  const auto lo = static_cast<std::size_t>(std::floor(at));
  const std::size_t hi = std::min(lo + 1, values.size() - 1);
  return values[lo] + (at - static_cast<double>(lo)) * (values[hi] - values[lo]);
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
