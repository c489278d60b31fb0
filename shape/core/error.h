// pectus: one project exception type at library boundaries (docs/errors.md).
#pragma once

#include <cstdint>
#include <stdexcept>
#include <string>

namespace pectus {

/// What kind of failure an Error is; the command line maps it to an exit code.
enum class ErrorKind {
  kUsage = 2,     ///< The caller asked for something impossible (bad option, output equals input).
  kBadInput = 3,  ///< A file or value given to pectus is wrong (malformed, degenerate, missing).
  kFailure = 1,   ///< Anything else: a computation that did not succeed, an I/O failure on write.
};

/// The one exception pectus throws across library boundaries.
///
/// what() reads "FILE:LINE: MESSAGE" (or "FILE: MESSAGE", or "MESSAGE") so that a user sees at once
/// which file and which line or item is at fault.
class Error : public std::runtime_error {
 public:
  /// @param[in] kind     what kind of failure (maps to the exit code)
  /// @param[in] message  what is wrong, in words a user understands
  /// @param[in] file     the file at fault, or empty
  /// @param[in] line     1-based line (or item) number at fault, or 0 for none
  Error(ErrorKind kind, std::string message, std::string file = {}, std::int64_t line = 0);

  ErrorKind kind() const { return kind_; }
  const std::string& file() const { return file_; }
  std::int64_t line() const { return line_; }
  /// The message without the file and line prefix.
  const std::string& message() const { return message_; }

 private:
  ErrorKind kind_;
  std::string message_;
  std::string file_;
  std::int64_t line_;
};

/// Throws Error(kBadInput) naming the file (and line when > 0).
[[noreturn]] void ThrowBadInput(const std::string& file, const std::string& message, std::int64_t line = 0);
/// Throws Error(kUsage).
[[noreturn]] void ThrowUsage(const std::string& message);
/// Throws Error(kFailure).
[[noreturn]] void ThrowFailure(const std::string& message, const std::string& file = {});

}  // namespace pectus
