// pectus: warnings and progress on the terminal.
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <mutex>
#include <string>
#include <vector>

namespace pectus {

/// Prints "pectus: warning: MESSAGE" to stderr (unless quiet) and hands it to every live WarningCollector.
void Warn(const std::string& message);
/// Prints "pectus: MESSAGE" to stderr unless quiet.
void Info(const std::string& message);
/// Collects every warning given (on any thread) while it lives: one command's report, one request, one
/// test. Nothing is kept once the last collector is gone, so a long-lived process (a server, a fuzzer)
/// does not accumulate them.
class WarningCollector {
 public:
  WarningCollector();
  ~WarningCollector();
  WarningCollector(const WarningCollector&) = delete;
  WarningCollector& operator=(const WarningCollector&) = delete;
  /// The warnings given since construction, in order.
  std::vector<std::string> warnings() const;

 private:
  friend void Warn(const std::string& message);
  std::vector<std::string> warnings_;  // guarded by the log's mutex
};

/// Silences Info and Warn output (warnings still reach the collectors).
void SetQuiet(bool quiet);
bool IsQuiet();

/// Progress of a long stage: a self-rewriting line on stderr when it is a terminal, nothing otherwise.
/// Advance() is thread-safe and cheap (redraws at most ten times a second).
class Progress {
 public:
  /// @param[in] label  what is being done ("reading sweeps")
  /// @param[in] total  number of steps, > 0
  Progress(std::string label, std::int64_t total);
  ~Progress();
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;
  void Advance(std::int64_t steps = 1);

 private:
  void Draw(std::int64_t done, bool final);
  std::string label_;
  std::int64_t total_;
  std::atomic<std::int64_t> done_{0};
  std::atomic<std::int64_t> last_draw_ns_{0};
  std::chrono::steady_clock::time_point start_;
  std::mutex draw_mutex_;
  bool enabled_;
};

}  // namespace pectus
