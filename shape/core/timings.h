// pectus: wall time per stage, the one shape in which every Result carries its timings (`timings_s`),
// as the JSON reports print them.
#pragma once

#include <chrono>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

namespace pectus {

/// Seconds of wall time since `start` (steady clock).
inline double SecondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

/// Wall time per stage in seconds, in the order the stages first ran; a stage that runs again is summed.
/// Every Result names its field `timings_s`.
class Timings {
 public:
  /// Times a stage from construction to destruction into a Timings (wall clock).
  class Scope {
   public:
    Scope(Timings* timings, std::string stage);
    ~Scope();
    Scope(const Scope&) = delete;
    Scope& operator=(const Scope&) = delete;
    /// Seconds since the stage started.
    double Elapsed() const;

   private:
    Timings* timings_;
    std::string stage_;
    std::chrono::steady_clock::time_point start_;
  };

  /// Starts timing a stage: `auto t = result.timings_s.Time("merge");`.
  [[nodiscard]] Scope Time(std::string stage) { return Scope(this, std::move(stage)); }
  /// Adds `seconds` to `stage` (appended if new).
  void Add(const std::string& stage, double seconds);
  /// Adds every stage of `other`, stage by stage (a cohort's total over its subjects).
  void Add(const Timings& other);
  /// Seconds of `stage`, 0 if it never ran.
  double Seconds(const std::string& stage) const;
  /// Sum over the stages (s).
  double Total() const;
  bool empty() const { return stages_.empty(); }
  /// (stage, seconds) in the order the stages first ran.
  const std::vector<std::pair<std::string, double>>& stages() const { return stages_; }
  /// {"stage": seconds, ...}.
  nlohmann::json ToJson() const;

 private:
  std::vector<std::pair<std::string, double>> stages_;
};

}  // namespace pectus
