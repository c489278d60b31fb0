#include "shape/core/report.h"

#include "shape/core/atomic_file.h"
#include "shape/core/log.h"

namespace pectus {

Report::StageTimer::StageTimer(Report* report, std::string name)
    : report_(report), name_(std::move(name)), start_(std::chrono::steady_clock::now()) {}

Report::StageTimer::~StageTimer() {
  if (report_ != nullptr) report_->AddTime(name_, Elapsed());
}

double Report::StageTimer::Elapsed() const {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
}

Report::Report() : json_(nlohmann::json::object()), start_(std::chrono::steady_clock::now()) {}

void Report::AddTime(const std::string& stage, double seconds) {
  auto& t = json_["timings_s"][stage];
  t = (t.is_number() ? t.get<double>() : 0.0) + seconds;
}

void Report::AddTimes(const Timings& timings) {
  for (const auto& [stage, seconds] : timings.stages()) AddTime(stage, seconds);
}

void Report::Write(const std::filesystem::path& path) {
  json_["timings_s"]["total"] =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  json_["warnings"] = warnings_.warnings();
  WriteFileAtomically(path, json_.dump(2) + "\n");
}

}  // namespace pectus
