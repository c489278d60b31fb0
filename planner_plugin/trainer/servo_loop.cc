#include "planner_plugin/trainer/servo_loop.h"

#include <algorithm>
#include <chrono>
#include <cstdio>

#if defined(__linux__)
#include <pthread.h>
#include <sched.h>
#include <sys/prctl.h>
#endif

#include "shape/core/error.h"
#include "shape/core/sample_statistics.h"

namespace pectus::trainer {

bool ServoLoopOptions::IsValid(std::string* why) const {
  const bool ok = rate_hz >= 1 && rate_hz <= 100000 && max_records >= 1 && spin_us >= 0 &&
                  spin_us * 1e-6 * rate_hz <= 1 && realtime_priority >= 0 && realtime_priority <= 99;
  if (!ok && why != nullptr) {
    *why =
        "servo loop: rate_hz must be 1 to 100000, max_records >= 1, spin_us 0 to a period, "
        "realtime_priority 0 to 99";
  }
  return ok;
}

std::string ServoLoopStatistics::BriefReport() const {
  char text[300];
  std::snprintf(
      text, sizeof(text),
      "%lld ticks; period mean %.4f ms, p50 %.4f, p99 %.4f, max %.3f; tick p50 %.1f us, p99 %.1f, max "
      "%.1f; %lld late%s",
      static_cast<long long>(ticks), period_mean_ms, period_p50_ms, period_p99_ms, period_max_ms, tick_p50_us,
      tick_p99_us, tick_max_us, static_cast<long long>(late_ticks), realtime ? "; SCHED_FIFO" : "");
  return text;
}

ServoLoop::ServoLoop(const ServoLoopOptions& options) : options_(options) {
  std::string why;
  if (!options.IsValid(&why)) ThrowUsage(why);
}

ServoLoop::~ServoLoop() { Stop(); }

namespace {

// The calling thread's timer slack to 1 ns (Linux's default is 50 us, by which a sleep may overrun), and
// SCHED_FIFO at `priority` if asked and allowed. Returns whether the thread is now SCHED_FIFO.
bool TuneServoThread(int priority) noexcept {
#if defined(__linux__)
  prctl(PR_SET_TIMERSLACK, 1UL, 0UL, 0UL, 0UL);
  if (priority <= 0) return false;
  sched_param parameter{};
  parameter.sched_priority = priority;
  return pthread_setschedparam(pthread_self(), SCHED_FIFO, &parameter) == 0;
#else
  (void)priority;
  return false;
#endif
}

}  // namespace

void ServoLoop::Start(std::function<void(double)> tick) {
  if (running_.load()) ThrowUsage("servo loop: already running");
  if (thread_.joinable()) thread_.join();
  periods_s_.assign(static_cast<std::size_t>(options_.max_records), 0.0);
  ticks_s_.assign(static_cast<std::size_t>(options_.max_records), 0.0);
  count_ = late_ = 0;
  realtime_ = false;
  running_.store(true);
  thread_ = std::thread([this, tick = std::move(tick)] {
    using Clock = std::chrono::steady_clock;
    realtime_ = TuneServoThread(options_.realtime_priority);
    const auto period =
        std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(1.0 / options_.rate_hz));
    const auto spin =
        std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(1e-6 * options_.spin_us));
    const Clock::time_point start = Clock::now();
    Clock::time_point deadline = start, last = start;
    std::int64_t n = 0;
    while (running_.load(std::memory_order_relaxed)) {
      const Clock::time_point begin = Clock::now();
      tick(std::chrono::duration<double>(begin - start).count());
      const Clock::time_point end = Clock::now();
      if (n > 0 && n - 1 < options_.max_records) {
        periods_s_[static_cast<std::size_t>(n - 1)] = std::chrono::duration<double>(begin - last).count();
        ticks_s_[static_cast<std::size_t>(n - 1)] = std::chrono::duration<double>(end - begin).count();
      }
      if (begin - deadline > period) ++late_;
      last = begin;
      ++n;
      deadline += period;
      // Sleep to shortly before the deadline, then spin on the clock up to it.
      std::this_thread::sleep_until(deadline - spin);
      while (Clock::now() < deadline && running_.load(std::memory_order_relaxed)) {
      }
    }
    count_ = n;
  });
}

void ServoLoop::Stop() {
  running_.store(false);
  if (thread_.joinable()) thread_.join();
}

ServoLoopStatistics ServoLoop::Statistics() const {
  ServoLoopStatistics s;
  s.ticks = count_;
  s.late_ticks = late_;
  s.realtime = realtime_;
  const std::size_t n =
      static_cast<std::size_t>(std::clamp<std::int64_t>(count_ - 1, 0, options_.max_records));
  std::vector<double> periods(periods_s_.begin(), periods_s_.begin() + static_cast<std::ptrdiff_t>(n));
  std::vector<double> ticks(ticks_s_.begin(), ticks_s_.begin() + static_cast<std::ptrdiff_t>(n));
  if (n == 0) return s;
  s.period_mean_ms = 1e3 * Mean(periods);
  s.period_p50_ms = 1e3 * Quantile(periods, 0.5);
  s.period_p99_ms = 1e3 * Quantile(periods, 0.99);
  s.period_max_ms = 1e3 * Max(periods);
  s.tick_p50_us = 1e6 * Quantile(ticks, 0.5);
  s.tick_p99_us = 1e6 * Quantile(ticks, 0.99);
  s.tick_max_us = 1e6 * Max(ticks);
  return s;
}

}  // namespace pectus::trainer
