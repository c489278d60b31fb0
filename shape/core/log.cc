#include "shape/core/log.h"

#include <unistd.h>

#include <algorithm>
#include <cstdio>

namespace pectus {
namespace {

std::mutex g_mutex;
std::vector<WarningCollector*> g_collectors;  // guarded by g_mutex
std::atomic<bool> g_quiet{false};

}  // namespace

void Warn(const std::string& message) {
  std::lock_guard<std::mutex> lock(g_mutex);
  for (WarningCollector* c : g_collectors) c->warnings_.push_back(message);
  if (!g_quiet) std::fprintf(stderr, "pectus: warning: %s\n", message.c_str());
}

void Info(const std::string& message) {
  if (!g_quiet) std::fprintf(stderr, "pectus: %s\n", message.c_str());
}

WarningCollector::WarningCollector() {
  std::lock_guard<std::mutex> lock(g_mutex);
  g_collectors.push_back(this);
}

WarningCollector::~WarningCollector() {
  std::lock_guard<std::mutex> lock(g_mutex);
  g_collectors.erase(std::find(g_collectors.begin(), g_collectors.end(), this));
}

std::vector<std::string> WarningCollector::warnings() const {
  std::lock_guard<std::mutex> lock(g_mutex);
  return warnings_;
}

void SetQuiet(bool quiet) { g_quiet = quiet; }
bool IsQuiet() { return g_quiet; }

Progress::Progress(std::string label, std::int64_t total)
    : label_(std::move(label)),
      total_(total > 0 ? total : 1),
      start_(std::chrono::steady_clock::now()),
      enabled_(!g_quiet && ::isatty(STDERR_FILENO) == 1) {
  if (enabled_) Draw(0, false);
}

Progress::~Progress() {
  if (enabled_) Draw(done_.load(), true);
}

void Progress::Advance(std::int64_t steps) {
  const std::int64_t done = done_.fetch_add(steps) + steps;
  if (!enabled_) return;
  const std::int64_t now =
      std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now() - start_).count();
  std::int64_t last = last_draw_ns_.load();
  if (now - last < 100'000'000 && done < total_) return;
  if (!last_draw_ns_.compare_exchange_strong(last, now)) return;
  Draw(done, false);
}

void Progress::Draw(std::int64_t done, bool final) {
  std::lock_guard<std::mutex> lock(draw_mutex_);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  const double fraction = static_cast<double>(done) / static_cast<double>(total_);
  std::fprintf(stderr, "\r\033[Kpectus: %s %3.0f%% (%lld/%lld) %.1fs", label_.c_str(), 100.0 * fraction,
               static_cast<long long>(done), static_cast<long long>(total_), seconds);
  if (final) std::fputc('\n', stderr);
  std::fflush(stderr);
}

}  // namespace pectus
