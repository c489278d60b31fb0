// pectus trainer: the haptic servo loop on its own thread, apart from drawing (as CHAI3D and the
// dissertation's Phantom driver run it): a tick every period on an absolute schedule (late ticks do not
// push the later ones), with the periods and the ticks' own durations kept in buffers sized up front for
// the statistics. The thread sleeps until shortly before each deadline and spins the rest (a sleeping
// thread wakes tens to hundreds of microseconds late, the timer's slack and the scheduler's latency;
// docs/trainer.md), with a timer slack of 1 ns, and asks for SCHED_FIFO when told to (kept silently
// as an ordinary thread when the system does not allow it).
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <string>
#include <thread>
#include <vector>

namespace pectus::trainer {

struct ServoLoopOptions {
  double rate_hz = 1000.0;            ///< ticks per second (1 kHz: the Phantom's servo rate)
  std::int64_t max_records = 120000;  ///< periods kept for the statistics (2 minutes at 1 kHz)
  /// Microseconds before each deadline at which the thread stops sleeping and spins on the clock; 0 sleeps
  /// to the deadline. 200 us (a fifth of a core at 1 kHz): the p99 of the wake-up's delay on the project's
  /// VM (docs/benchmarks.md).
  double spin_us = 200;
  /// SCHED_FIFO priority asked for the thread (1-99); 0 leaves it an ordinary thread. Refused (no
  /// privilege, not Linux): the thread runs as an ordinary one, ServoLoopStatistics::realtime says which.
  int realtime_priority = 0;
  bool IsValid(std::string* why) const;
};

/// Periods and tick durations of a run, in milliseconds and microseconds.
struct ServoLoopStatistics {
  std::int64_t ticks = 0;
  double period_mean_ms = 0, period_p50_ms = 0, period_p99_ms = 0, period_max_ms = 0;
  double tick_p50_us = 0, tick_p99_us = 0, tick_max_us = 0;
  std::int64_t late_ticks = 0;  ///< ticks that started more than a period after their deadline
  bool realtime = false;        ///< the thread ran under SCHED_FIFO
  std::string BriefReport() const;
};

/// Runs `tick(time_s)` on a thread at the rate until Stop(). The tick must not block.
class ServoLoop {
 public:
  explicit ServoLoop(const ServoLoopOptions& options = {});
  ~ServoLoop();
  ServoLoop(const ServoLoop&) = delete;
  ServoLoop& operator=(const ServoLoop&) = delete;
  /// Starts the thread (Error(kUsage) if running). time_s counts from the start.
  void Start(std::function<void(double time_s)> tick);
  /// Stops and joins the thread (no-op if not running).
  void Stop();
  bool running() const { return running_.load(); }
  /// The statistics of the last run (after Stop()).
  ServoLoopStatistics Statistics() const;

 private:
  ServoLoopOptions options_;
  std::atomic<bool> running_{false};
  std::thread thread_;
  std::vector<double> periods_s_, ticks_s_;
  std::int64_t count_ = 0, late_ = 0;
  bool realtime_ = false;
};

}  // namespace pectus::trainer
