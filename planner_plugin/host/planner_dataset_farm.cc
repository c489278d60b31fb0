#include "planner_plugin/host/planner_dataset_farm.h"

#include <algorithm>
#include <chrono>
#include <exception>
#include <fstream>
#include <mutex>
#include <sstream>

#include "planner_plugin/host/planner_client.h"
#include "shape/core/atomic_file.h"
#include "shape/core/error.h"
#include "shape/core/number_format.h"
#include "shape/io/patient_table_io.h"

namespace pectus::planner {
namespace {

namespace fs = std::filesystem;

std::string ReadText(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

// The parts of one table in `work/parts`: ID.h5 once made, ID.failed (the reason) if it failed, and
// ID.seconds (the task's wall time) beside either.
class PartStore {
 public:
  PartStore(const fs::path& work, const std::vector<PatientTableRow>& rows) : folder_(work / "parts") {
    for (const PatientTableRow& row : rows) ids_.push_back(std::to_string(row.patient));
  }
  const std::string& id(int i) const { return ids_[i]; }
  fs::path Part(int i) const { return folder_ / (ids_[i] + ".h5"); }
  fs::path Failure(int i) const { return folder_ / (ids_[i] + ".failed"); }
  fs::path Seconds(int i) const { return folder_ / (ids_[i] + ".seconds"); }
  fs::path Setup(int i) const { return folder_ / (ids_[i] + ".setup"); }
  bool Done(int i) const {
    std::error_code ec;
    return fs::exists(Part(i), ec) || fs::exists(Failure(i), ec);
  }
  // The patients without a part or a failure, in table order.
  std::vector<int> Missing() const {
    std::vector<int> missing;
    for (int i = 0; i < static_cast<int>(ids_.size()); ++i) {
      if (!Done(i)) missing.push_back(i);
    }
    return missing;
  }
  DatasetPatient Outcome(int i) const {
    DatasetPatient p;
    p.id = ids_[i];
    std::error_code ec;
    p.ok = fs::exists(Part(i), ec);
    if (!p.ok) p.error = ReadText(Failure(i));
    if (fs::exists(Seconds(i), ec)) p.seconds = ReadExactText(Seconds(i).string());
    if (fs::exists(Setup(i), ec)) p.setup_seconds = ReadExactText(Setup(i).string());
    return p;
  }

 private:
  fs::path folder_;
  std::vector<std::string> ids_;
};

// The leader's part of BuildPlannerDatasetOnFarm: the patients' outcomes, and the dataset from the parts
// of those that made it, in table order.
void Assemble(const PlannerPlugin& plugin, const fs::path& table, const fs::path& output,
              const PartStore& parts, int n, DatasetFarmResult* result) {
  std::vector<std::string> paths;
  for (int i = 0; i < n; ++i) {
    result->patients.push_back(parts.Outcome(i));
    if (result->patients.back().ok) paths.push_back(parts.Part(i).string());
  }
  if (paths.empty()) {
    ThrowFailure("FE dataset: no patient of the table could be built (first: patient " +
                     result->patients.front().id + ": " + result->patients.front().error + ")",
                 table.string());
  }
  std::vector<const char*> c_paths;
  for (const std::string& p : paths) c_paths.push_back(p.c_str());
  PectusPlannerStatus status{};
  ThrowIfFailed(plugin.api().assemble_dataset(c_paths.data(), static_cast<std::int64_t>(c_paths.size()),
                                              output.c_str(), &result->summary, &status),
                status);
  result->assemble_seconds = result->summary.seconds;
  result->written = true;
}

}  // namespace

void RemoveDatasetParts(const fs::path& work) {
  std::error_code ec;
  fs::remove_all(work / "parts", ec);
  if (ec) ThrowFailure("cannot remove the dataset's parts: " + ec.message(), (work / "parts").string());
  if (fs::is_empty(work, ec)) fs::remove(work, ec);
}

DatasetFarmResult BuildPlannerDatasetOnFarm(const PlannerPlugin& plugin, const fs::path& table,
                                            const fs::path& output, const PectusPlannerOptions& options,
                                            const PectusPlannerBasisOptions* basis, const DatasetFarm& farm,
                                            const std::function<void(const DatasetPatient&)>& done) {
  if (farm.work.empty()) ThrowUsage("FE dataset: the farm needs a work folder for the patients' parts");
  SerialTaskRunner serial;
  TaskRunner& runner = farm.runner != nullptr ? *farm.runner : serial;
  const std::vector<PatientTableRow> rows = ReadPatientTable(table);
  const PartStore parts(farm.work, rows);
  const auto n = static_cast<int>(rows.size());
  if (runner.IsLeader()) {
    if (!farm.resume) RemoveDatasetParts(farm.work);
    std::error_code ec;
    fs::create_directories(farm.work / "parts", ec);
    if (ec) ThrowFailure("cannot create the parts' folder: " + ec.message(), (farm.work / "parts").string());
  }
  runner.Barrier();
  const std::vector<int> missing = parts.Missing();
  if (farm.gather && !missing.empty()) {
    std::vector<std::string> ids;
    for (int i : missing) ids.push_back(parts.id(i));
    ThrowUsage("--gather: no share has made patient(s) " + NamesForMessage(ids) +
               " (their parts are not in " + (farm.work / "parts").string() +
               "); run their shares, or the whole run with --resume");
  }

  // Each patient's part, in table order (their costs are alike): a failure is recorded, not thrown.
  std::mutex done_mutex;
  std::vector<fs::path> made_here;
  runner.Run(missing, [&](int i) {
    const auto start = std::chrono::steady_clock::now();
    PectusPlannerDatasetSummary summary{};
    PectusPlannerStatus status{};
    const std::int32_t code = plugin.api().write_dataset_part(table.c_str(), i, parts.Part(i).c_str(),
                                                              &options, basis, &summary, &status);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    // After the part (lost if killed in between): the task's time, and what of it was not the part's own.
    WriteFileAtomically(parts.Seconds(i), ExactText(seconds));
    if (code == PECTUS_PLANNER_OK) {
      WriteFileAtomically(parts.Setup(i), ExactText(std::max(0.0, seconds - summary.seconds)));
    } else {
      WriteFileAtomically(parts.Failure(i), status.message[0] != '\0' ? status.message : "the plugin failed");
    }
    const std::lock_guard<std::mutex> lock(done_mutex);
    for (const fs::path& file : {parts.Part(i), parts.Failure(i), parts.Seconds(i), parts.Setup(i)}) {
      made_here.push_back(file);
    }
    if (done) done(parts.Outcome(i));
  });
  DatasetFarmResult result;
  result.built = static_cast<int>(missing.size());
  result.made_here = std::move(made_here);
  if (farm.parts_only) return result;

  // The dataset from the parts of the patients that made it, in table order, on the leader; whether it
  // was made, to every process (they wait for it to remove their parts: RemoveDatasetPartsOnFarm).
  std::string why;
  std::exception_ptr failed;
  if (runner.IsLeader()) {
    try {
      Assemble(plugin, table, output, parts, n, &result);
    } catch (const std::exception& e) {
      failed = std::current_exception();
      why = e.what();
    }
  }
  if (!runner.BroadcastOutcome(failed == nullptr, &why)) {
    if (failed) std::rethrow_exception(failed);
    ThrowFailure("the leader could not assemble the dataset: " + why);
  }
  return result;
}

double RemoveDatasetPartsOnFarm(const DatasetFarm& farm, const DatasetFarmResult& result, bool remove) {
  SerialTaskRunner serial;
  TaskRunner& runner = farm.runner != nullptr ? *farm.runner : serial;
  std::string why;
  if (!runner.BroadcastOutcome(remove, &why)) return 0.0;
  const auto start = std::chrono::steady_clock::now();
  std::error_code ec;
  for (const fs::path& file : result.made_here) fs::remove(file, ec);  // what is left, the leader removes
  runner.Barrier();
  if (runner.IsLeader()) RemoveDatasetParts(farm.work);
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace pectus::planner
