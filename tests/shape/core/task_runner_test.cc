// The serial task farm (shape/core/task_runner.h): every task run once, a share runs its tasks only, a
// failing task stops neither the others nor hides its message; shares parsed from K/N; largest first.
#include "shape/core/task_runner.h"

#include <gtest/gtest.h>

#include <atomic>
#include <stdexcept>
#include <vector>

#include "shape/core/error.h"

namespace pectus {
namespace {

TEST(TaskRunner, RunsEveryTaskOnce) {
  std::vector<std::atomic<int>> runs(50);
  SerialTaskRunner runner;
  runner.Run(LargestFirst(std::vector<double>(50, 1.0)), [&](int i) { ++runs[i]; });
  for (int i = 0; i < 50; ++i) EXPECT_EQ(runs[i], 1) << "task " << i;
  EXPECT_TRUE(runner.IsLeader());
  EXPECT_EQ(runner.Processes(), 1);
}

TEST(TaskRunner, SharesSplitTheTasksWithoutOverlap) {
  std::vector<std::atomic<int>> runs(10);
  std::vector<int> order{9, 3, 0, 1, 2, 4, 5, 6, 7, 8};
  for (int k = 1; k <= 3; ++k) {
    SerialTaskRunner share(ParseTaskShare(std::to_string(k) + "/3"));
    share.Run(order, [&](int i) {
      EXPECT_EQ(i % 3, k - 1) << "share " << k << " ran task " << i;
      ++runs[i];
    });
  }
  for (int i = 0; i < 10; ++i) EXPECT_EQ(runs[i], 1) << "task " << i;
}

TEST(TaskRunner, AFailingTaskLetsTheOthersRunAndIsReported) {
  std::vector<std::atomic<int>> runs(8);
  SerialTaskRunner runner;
  try {
    runner.Run({0, 1, 2, 3, 4, 5, 6, 7}, [&](int i) {
      ++runs[i];
      if (i == 5) throw std::runtime_error("subject 5 could not be written");
    });
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::kFailure);
    EXPECT_NE(std::string(e.what()).find("subject 5 could not be written"), std::string::npos) << e.what();
  }
  for (int i = 0; i < 8; ++i) EXPECT_EQ(runs[i], 1) << "task " << i;
}

TEST(TaskRunner, ParsesSharesAndRefusesOthers) {
  const TaskShare s = ParseTaskShare("2/7");
  EXPECT_EQ(s.index, 2);
  EXPECT_EQ(s.count, 7);
  EXPECT_TRUE(s.Holds(1));
  EXPECT_TRUE(s.Holds(8));
  EXPECT_FALSE(s.Holds(2));
  EXPECT_TRUE(ParseTaskShare("1/1").whole());
  for (const char* bad : {"0/3", "4/3", "3", "a/b", "1/3x", "/3", "1/0", "-1/3"}) {
    try {
      ParseTaskShare(bad);
      ADD_FAILURE() << bad << " was accepted";
    } catch (const Error& e) {
      EXPECT_EQ(e.kind(), ErrorKind::kUsage) << bad;
      EXPECT_NE(std::string(e.what()).find(bad), std::string::npos) << e.what();
    }
  }
}

TEST(TaskRunner, LargestFirstKeepsTiesInIndexOrder) {
  EXPECT_EQ(LargestFirst({1.0, 5.0, 2.0, 5.0, 0.0}), (std::vector<int>{1, 3, 2, 0, 4}));
  EXPECT_TRUE(LargestFirst({}).empty());
}

}  // namespace
}  // namespace pectus
