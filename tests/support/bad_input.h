// The message of the Error(kBadInput) a reader throws, for the tests of every reader: any other outcome
// (no error, another kind, another file, an exception that is not pectus::Error) fails the test.
#pragma once

#include <gtest/gtest.h>

#include <exception>
#include <string>

#include "shape/core/error.h"

namespace pectus::testing_support {

/// Calls `read` and returns the message of the Error(kBadInput) naming `file` that it throws; records a
/// test failure for any other outcome.
template <class F>
std::string BadInputMessage(F&& read, const std::string& file) {
  try {
    read();
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::kBadInput) << e.what();
    EXPECT_EQ(e.file(), file) << e.what();
    return e.what();
  } catch (const std::exception& e) {
    ADD_FAILURE() << "not pectus::Error: " << e.what();
    return {};
  }
  ADD_FAILURE() << "no error";
  return {};
}

}  // namespace pectus::testing_support
