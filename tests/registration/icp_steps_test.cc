// Tests of registration/internal/icp_steps.h: step 1's certified reuse of correspondences (ICP-2 in
// docs/registration.md) gives exactly the pairs of searching the tree every time.
#include "registration/internal/icp_steps.h"

#include <gtest/gtest.h>

#include <random>
#include <string>

#include "chest_pair_problem.h"

namespace pectus::icp_detail {
namespace {

using testing::ChestPairProblem;

// Along a path of poses such as ICP walks (large steps, then ever smaller ones, and a jump back), the
// pairs found with certificates carried from pose to pose are those of a full search at every pose, and
// most poses need few searches; so are the planes through the nearest four target points.
TEST(FindPairs, CertifiedReuseEqualsSearchingEveryTime) {
  ChestPairProblem chest;
  const IcpTarget& prepared = chest.prepared;
  IcpOptions& options = chest.options;
  const Problem pb = chest.Make();
  const std::vector<std::uint32_t> sample = chest.AllRows();

  // The nearest point's own plane, and the plane through the nearest four (exact certificates for all four).
  for (const int plane_points : {1, 4}) {
    SCOPED_TRACE("plane_points " + std::to_string(plane_points));
    options.plane_points = plane_points;
    const double gate = 3.0 * prepared.spacing_mm();
    NearestCache cache;
    cache.Reset(sample.size(), kSearchRadiusOverGate * gate);
    Pairs reused, searched;
    std::mt19937_64 rng(11);
    // The source in the target's centred frame, then moved step by step.
    Rigid3 T = chest.Start();
    std::int64_t reused_searches = 0, full_searches = 0, matched = 0;
    const double steps_mm[] = {1.0, 0.3, 0.1, 0.03, 0.01, 0.003, 0.001, 0.5, 0.01, 0.002};
    for (const double step : steps_mm) {
      T = pectus::testing::RandomPose(&rng, step / 100.0, step, T.translation()) * T;  // 100 mm lever
      reused_searches += FindPairs(pb, sample, T, gate, &cache, &reused);
      full_searches += FindPairs(pb, sample, T, gate, nullptr, &searched);
      ASSERT_EQ(reused.target, searched.target) << "step " << step << " mm";
      for (std::size_t k = 0; k < sample.size(); ++k) {
        if (searched.target[k] == kNoMatch) continue;
        ++matched;
        ASSERT_EQ(reused.r[k], searched.r[k]) << "point " << k;
      }
    }
    // The two scans overlap on most of the source; the first pose searches every point, the small steps
    // almost none.
    EXPECT_GT(matched, 10 * 15000);
    EXPECT_EQ(full_searches, 10 * 20000);
    EXPECT_LT(reused_searches, 2 * 20000) << "certificates renewed too often";
  }
}

}  // namespace
}  // namespace pectus::icp_detail
