#include "shape/core/timings.h"

#include <gtest/gtest.h>

#include <thread>

namespace pectus {
namespace {

TEST(Timings, StagesKeepTheirOrderAndSumWhenRepeated) {
  Timings t;
  t.Add("read", 1.5);
  t.Add("merge", 2.0);
  t.Add("read", 0.25);
  ASSERT_EQ(t.stages().size(), 2u);
  EXPECT_EQ(t.stages()[0].first, "read");
  EXPECT_EQ(t.stages()[1].first, "merge");
  EXPECT_DOUBLE_EQ(t.Seconds("read"), 1.75);
  EXPECT_DOUBLE_EQ(t.Seconds("never"), 0.0);
  EXPECT_DOUBLE_EQ(t.Total(), 3.75);
  EXPECT_DOUBLE_EQ(t.ToJson()["merge"].get<double>(), 2.0);
}

TEST(Timings, TotalsOverSubjectsStageByStage) {
  Timings a, b, total;
  a.Add("merge", 1.0);
  b.Add("reconstruct", 3.0);
  b.Add("merge", 2.0);
  total.Add(a);
  total.Add(b);
  EXPECT_DOUBLE_EQ(total.Seconds("merge"), 3.0);
  EXPECT_DOUBLE_EQ(total.Seconds("reconstruct"), 3.0);
  EXPECT_EQ(total.stages()[0].first, "merge");
}

TEST(Timings, ScopeMeasuresWallTime) {
  Timings t;
  {
    auto s = t.Time("sleep");
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  EXPECT_GE(t.Seconds("sleep"), 0.019);
  EXPECT_LT(t.Seconds("sleep"), 5.0);  // generous: a loaded machine may stall the thread
}

}  // namespace
}  // namespace pectus
