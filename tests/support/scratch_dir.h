// A test fixture that gives every test its own empty folder, removed again after the test.
#pragma once

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstddef>
#include <filesystem>
#include <iterator>
#include <string>
#include <utility>

namespace pectus::testing_support {

class ScratchDirTest : public ::testing::Test {
 protected:
  /// The folder is <temp>/<prefix><test name>_<process id>: two suites running at once (a Release and a
  /// sanitizer build, or two checkouts) never share one.
  explicit ScratchDirTest(std::string prefix) : prefix_(std::move(prefix)) {}

  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() /
           (prefix_ + ::testing::UnitTest::GetInstance()->current_test_info()->name() + "_" +
            std::to_string(getpid()));
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }

  /// The path of `name` inside the test's folder.
  std::string P(const std::string& name) const { return (dir_ / name).string(); }
  /// How many entries the test's folder holds (to check that a failed run wrote nothing).
  std::size_t CountFiles() const {
    return static_cast<std::size_t>(std::distance(std::filesystem::directory_iterator(dir_), {}));
  }

  std::filesystem::path dir_;

 private:
  std::string prefix_;
};

}  // namespace pectus::testing_support
