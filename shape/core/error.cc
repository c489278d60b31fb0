#include "shape/core/error.h"

namespace pectus {
namespace {

std::string Compose(const std::string& message, const std::string& file, std::int64_t line) {
  if (file.empty()) return message;
  if (line > 0) return file + ":" + std::to_string(line) + ": " + message;
  return file + ": " + message;
}

}  // namespace

Error::Error(ErrorKind kind, std::string message, std::string file, std::int64_t line)
    : std::runtime_error(Compose(message, file, line)),
      kind_(kind),
      message_(std::move(message)),
      file_(std::move(file)),
      line_(line) {}

void ThrowBadInput(const std::string& file, const std::string& message, std::int64_t line) {
  throw Error(ErrorKind::kBadInput, message, file, line);
}

void ThrowUsage(const std::string& message) { throw Error(ErrorKind::kUsage, message); }

void ThrowFailure(const std::string& message, const std::string& file) {
  throw Error(ErrorKind::kFailure, message, file);
}

}  // namespace pectus
