// pectus registration benchmark (issue 4), part "pairs": seeded trials of chest scan pairs (0.2 mm surface
// noise, the second scan's frame off by up to 10 degrees and 30 mm, 3 mm landmark noise per axis): the
// fraction within 0.05 degrees and 0.1 mm, and whether every other trial reported failure. Included once,
// by registration_benchmark.cc.
#pragma once

#include <iostream>

#include "registration/register_pair.h"
#include "tests/benchmarks/registration_benchmark_data.h"

namespace pectus {
namespace {

json Pairs(int trials, int icp_only_trials) {
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
    const NoisyChestPair c = MakeNoisyChestPair(seed);
    const ScanPair& p = c.pair;
    points += p.fixed.size() + p.moving.size();
    const LandmarkSet& lf = c.fixed_landmarks;
    const LandmarkSet& lm = c.moving_landmarks;
    for (const bool landmarks : {true, false}) {
      if (!landmarks && k >= icp_only_trials) continue;
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
    const int n = landmarks ? trials : std::min(trials, icp_only_trials);
    if (n == 0) return json{{"trials", 0}};
    std::sort(t.rot.begin(), t.rot.end());
    std::sort(t.trans.begin(), t.trans.end());
    auto at = [](const std::vector<double>& v, double q) {
      return v[std::min(v.size() - 1, static_cast<std::size_t>(q * static_cast<double>(v.size())))];
    };
    return json{
        {"trials", n},
        {"within_tolerance", t.within},
        {"within_fraction", static_cast<double>(t.within) / n},
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

}  // namespace
}  // namespace pectus
