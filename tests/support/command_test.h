// A fixture for tests of the `pectus` binary: every test gets its own scratch folder
// (<temp>/pectus_<suite>_<test>), runs the binary as a user would, and checks bad input the way every
// command must meet it (docs/errors.md): exit code 3, a message naming the file, nothing written.
#pragma once

#include <gtest/gtest.h>

#include <cstddef>
#include <fstream>
#include <string>

#include "tests/support/cli_run.h"
#include "tests/support/scratch_dir.h"

namespace pectus::testing_support {

class CommandTest : public ScratchDirTest {
 protected:
  using CliRun = testing_support::CliRun;

  CommandTest()
      : ScratchDirTest(
            "pectus_" +
            std::string(::testing::UnitTest::GetInstance()->current_test_info()->test_suite_name()) + "_") {}

  /// Runs `pectus ARGS` (see testing_support::Pectus).
  static CliRun Pectus(const std::string& args) { return testing_support::Pectus(args); }

  /// Writes `text` to `name` in the test's folder.
  void Write(const std::string& name, const std::string& text) const { std::ofstream(P(name)) << text; }

  /// `pectus ARGS` exits with 3, its output names `file` and says `fragment`, and it writes nothing.
  void ExpectBadInput(const std::string& args, const std::string& file, const std::string& fragment) const {
    const std::size_t before = CountFiles();
    const CliRun run = Pectus(args);
    EXPECT_EQ(run.code, 3) << run.output;
    EXPECT_NE(run.output.find(file), std::string::npos) << run.output;
    EXPECT_NE(run.output.find(fragment), std::string::npos) << run.output;
    EXPECT_EQ(CountFiles(), before) << "a failed run left a file behind";
  }
};

}  // namespace pectus::testing_support
