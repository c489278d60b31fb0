// The two helpers every options check of the generators uses (ChestParameters, SynthOptions, the scan
// simulator's options): a value within its range, and a reason written for the caller.
#pragma once

#include <cmath>
#include <string>

namespace pectus::datasets::internal {

/// True if `x` is finite and within [lo, hi].
inline bool InRange(double x, double lo, double hi) { return std::isfinite(x) && x >= lo && x <= hi; }

/// Writes `message` to `*why` (when given) and returns false: the tail of an `IsValid(std::string* why)`.
inline bool Fail(std::string* why, const std::string& message) {
  if (why != nullptr) *why = message;
  return false;
}

}  // namespace pectus::datasets::internal
