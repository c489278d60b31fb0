#include "shape/core/log.h"

#include <gtest/gtest.h>

#include <optional>
#include <string>
#include <thread>
#include <vector>

namespace pectus {
namespace {

// Warnings reach every collector alive when they are given, from any thread, and no other: nested scopes
// each see their own span; once none is alive nothing is kept.
TEST(WarningCollector, SeesTheWarningsGivenWhileItLives) {
  const bool quiet = IsQuiet();
  SetQuiet(true);
  Warn("before any collector");
  std::vector<std::string> inner_seen;
  const WarningCollector outer;
  Warn("first");
  {
    const WarningCollector inner;
    std::thread([] { Warn("from another thread"); }).join();
    inner_seen = inner.warnings();
  }
  Warn("last");
  SetQuiet(quiet);
  EXPECT_EQ(inner_seen, std::vector<std::string>({"from another thread"}));
  EXPECT_EQ(outer.warnings(), std::vector<std::string>({"first", "from another thread", "last"}));
  std::optional<WarningCollector> later;
  later.emplace();
  EXPECT_TRUE(later->warnings().empty());
}

}  // namespace
}  // namespace pectus
