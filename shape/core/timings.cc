#include "shape/core/timings.h"

#include <algorithm>

namespace pectus {

Timings::Scope::Scope(Timings* timings, std::string stage)
    : timings_(timings), stage_(std::move(stage)), start_(std::chrono::steady_clock::now()) {}

Timings::Scope::~Scope() {
  if (timings_ != nullptr) timings_->Add(stage_, Elapsed());
}

double Timings::Scope::Elapsed() const {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
}

void Timings::Add(const std::string& stage, double seconds) {
  auto it = std::find_if(stages_.begin(), stages_.end(), [&](const auto& s) { return s.first == stage; });
  if (it == stages_.end()) {
    stages_.emplace_back(stage, seconds);
  } else {
    it->second += seconds;
  }
}

void Timings::Add(const Timings& other) {
  for (const auto& [stage, seconds] : other.stages_) Add(stage, seconds);
}

double Timings::Seconds(const std::string& stage) const {
  for (const auto& [name, seconds] : stages_) {
    if (name == stage) return seconds;
  }
  return 0.0;
}

double Timings::Total() const {
  double total = 0.0;
  for (const auto& s : stages_) total += s.second;
  return total;
}

nlohmann::json Timings::ToJson() const {
  nlohmann::json j = nlohmann::json::object();
  for (const auto& [stage, seconds] : stages_) j[stage] = seconds;
  return j;
}

}  // namespace pectus
