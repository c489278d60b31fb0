// Tests that read the shared datasets folder: without it they say what is missing and where it comes
// from, and are skipped; under CI (the environment variable CI=true) they fail with the same message, so
// a CI run never passes without its real data.
#pragma once

#include <gtest/gtest.h>

#include <cstdlib>
#include <cstring>
#include <string>

#include "tests/support/shared_data.h"

namespace pectus::testing_support {

/// True when the environment variable CI is "true" or "1", as CI services set it.
inline bool UnderCi() {
  const char* ci = std::getenv("CI");
  return ci != nullptr && (std::strcmp(ci, "true") == 0 || std::strcmp(ci, "1") == 0);
}

}  // namespace pectus::testing_support

/// In a test body or a fixture's SetUp(): unless `relative` (e.g. testing_support::kPatientTable) is in the
/// shared folder, skips the test (outside CI) or fails it (under CI) with MissingSharedFile's message, and
/// returns. In SetUp() the test body is then not run.
#define PECTUS_REQUIRE_SHARED_FILE(relative)                                                    \
  do {                                                                                          \
    const std::string pectus_missing_ = ::pectus::testing_support::MissingSharedFile(relative); \
    if (!pectus_missing_.empty()) {                                                             \
      if (::pectus::testing_support::UnderCi()) {                                               \
        FAIL() << pectus_missing_ << " (CI=true: the shared data is required)";                 \
      }                                                                                         \
      GTEST_SKIP() << pectus_missing_;                                                          \
    }                                                                                           \
  } while (false)
