// `pectus surrogate check` as a user runs it (apps/commands/surrogate_command.cc), on a coarse mesh:
// the exact response basis reproduces the direct FE solve of the 24 dissertation cases and random bars
// to the 0.01 mm; a limit the basis cannot meet fails the run with the reason; bad input is a
// usage error naming what is wrong.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "tests/support/cli_run.h"
#include "tests/support/require_shared_data.h"

namespace pectus {
namespace {
namespace fs = std::filesystem;
using testing_support::Pectus;

const std::string kTable = testing_support::SharedPath(testing_support::kPatientTable);

TEST(SurrogateCommand, CheckHoldsTheBasisToTheDirectSolveAndFailsALimitItCannotMeet) {
  PECTUS_REQUIRE_SHARED_FILE(testing_support::kPatientTable);
  const fs::path dir = fs::temp_directory_path() / ("pectus_surrogate_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const std::string common = "surrogate check --patient-table '" + kTable +
                             "' --patients 57 --random 6 --evaluations 20 --cell-mm 10 --threads 1";
  const auto run = Pectus(common + " --report '" + (dir / "r.json").string() + "'");
  ASSERT_EQ(run.code, 0) << run.output;
  std::ifstream in(dir / "r.json");
  const nlohmann::json r = nlohmann::json::parse(in);
  ASSERT_EQ(r["patients"].size(), 1u);
  const nlohmann::json& p = r["patients"][0];
  EXPECT_EQ(p["patient"], "57");
  EXPECT_EQ(p["cases"].get<int>(), 24 + 6);
  EXPECT_LT(p["max_difference_mm"].get<double>(), 0.01);
  EXPECT_LT(p["max_lift_difference_mm"].get<double>(), 0.01);
  EXPECT_GT(p["rank"].get<int>(), 0);
  EXPECT_LE(p["truncation_bound_mm"].get<double>(), 0.001);
  EXPECT_GT(p["update_median_us"].get<double>(), 0.0);
  // A limit below what a compressed basis can hold: the run fails (exit 1) and says why.
  const auto strict = Pectus(common + " --tolerance-mm 0.5 --limit-mm 1e-9");
  EXPECT_EQ(strict.code, 1) << strict.output;
  EXPECT_NE(strict.output.find("does not reproduce the FE solve"), std::string::npos) << strict.output;
  // Bad input.
  const auto none = Pectus("surrogate check --patient-table '" + kTable + "' --patients ,");
  EXPECT_EQ(none.code, 2) << none.output;
  EXPECT_NE(none.output.find("names no patient"), std::string::npos) << none.output;
  const auto unknown = Pectus("surrogate check --patient-table '" + kTable + "' --patients 999");
  EXPECT_NE(unknown.code, 0) << unknown.output;
  EXPECT_NE(unknown.output.find("999"), std::string::npos) << unknown.output;
  fs::remove_all(dir);
}

}  // namespace
}  // namespace pectus
