// pectus: the JSON report every command can write (--report FILE.json), with timings per stage.
#pragma once

#include <chrono>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "shape/core/log.h"
#include "shape/core/timings.h"

namespace pectus {

/// What a command did: free-form JSON plus timings per stage under "timings_s".
class Report {
 public:
  /// Times a stage from construction to destruction into report["timings_s"][name] (seconds, summed if
  /// the same stage runs more than once).
  class StageTimer {
   public:
    StageTimer(Report* report, std::string name);
    ~StageTimer();
    StageTimer(const StageTimer&) = delete;
    StageTimer& operator=(const StageTimer&) = delete;
    /// Seconds since the stage started.
    double Elapsed() const;

   private:
    Report* report_;
    std::string name_;
    std::chrono::steady_clock::time_point start_;
  };

  Report();
  /// Starts timing a stage: `auto t = report.Stage("read");`.
  [[nodiscard]] StageTimer Stage(std::string name) { return StageTimer(this, std::move(name)); }
  /// Adds seconds to a stage.
  void AddTime(const std::string& stage, double seconds);
  /// Adds every stage of a Result's `timings_s`.
  void AddTimes(const Timings& timings);
  nlohmann::json& json() { return json_; }
  const nlohmann::json& json() const { return json_; }
  nlohmann::json& operator[](const std::string& key) { return json_[key]; }
  /// Writes the report atomically, pretty-printed, with total wall time and the warnings given since it
  /// was made.
  void Write(const std::filesystem::path& path);

 private:
  nlohmann::json json_;
  std::chrono::steady_clock::time_point start_;
  WarningCollector warnings_;  // the warnings given while this report lives
};

}  // namespace pectus
