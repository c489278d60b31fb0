// `pectus pipeline` on a task farm (docs/cluster.md), as a user runs it: on MPI ranks (`mpirun -n 1, 2,
// 3`), in shares gathered afterwards (`--shard K/3`, then `--gather`, which refuses while a share is
// missing), and killed half way then resumed (`--resume`). Each run's outputs are compared byte for byte
// with the serial run's on one 6-subject cohort; report.html is compared without what a run cannot
// repeat: its run facts (the command, threads, summed stage times) and the per-subject wall times.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <regex>
#include <sstream>
#include <string>

#include "tests/support/cli_run.h"
#include "tests/support/cluster_run.h"
#include "tests/support/scratch_dir.h"

namespace pectus {
namespace {
namespace fs = std::filesystem;

using testing_support::CliRun;
using testing_support::Pectus;

// Coarse enough to take seconds under the sanitizers, fine enough to reconstruct (pipeline_command_test).
// --impute-others 3: the imputation's core is 4 subjects, and the other 2 are filled from it, so that the
// model's collective steps (the core's sweeps, the fills beyond it, the local corrections, the Gram
// matrix, the basis and the scores: BuildModel) are each shared among the ranks.
const char* const kOptions =
    " --grid 21x41 --surface-spacing 3 --merge-spacing 0 --no-quality --impute-others 3 --quiet";

// report.html without its run facts, the summed stage times and each subject's time (the last cell of a
// subject's row): the only parts that depend on the run rather than on the cohort.
std::string WithoutWallTimes(const std::string& html) {
  std::istringstream in(html);
  std::string kept;
  static const std::regex last_cell("<td>[0-9.]+</td></tr>$");
  for (std::string line; std::getline(in, line);) {
    if (line.rfind("<table><tr><th>command</th>", 0) == 0) continue;
    if (line.find("Stage times per subject") != std::string::npos) continue;
    if (line.rfind("<tr><td class=\"l\">", 0) == 0) line = std::regex_replace(line, last_cell, "</tr>");
    kept += line + "\n";
  }
  return kept;
}

// Every output file under `folder`, report.html without what a run cannot repeat.
std::map<std::string, std::string> Outputs(const fs::path& folder) {
  std::map<std::string, std::string> files = testing_support::FilesUnder(folder);
  if (auto html = files.find("report.html"); html != files.end())
    html->second = WithoutWallTimes(html->second);
  return files;
}

class PipelineCluster : public testing_support::ScratchDirTest {
 protected:
  PipelineCluster() : ScratchDirTest("pectus_pipeline_cluster_") {}

  // One cohort and its serial run for the suite's tests in this process.
  static void SetUpTestSuite() {
    setenv("SOURCE_DATE_EPOCH", "1700000000", 1);  // the model file's build time (statismo_io.cc)
    // One folder per process: CTest runs each test in a process of its own, several at once.
    suite_ = fs::temp_directory_path() / ("pectus_pipeline_cluster_suite_" + std::to_string(getpid()));
    fs::remove_all(suite_);
    fs::create_directories(suite_);
    CliRun run = Pectus("synth cohort --subjects 6 --seed 3 --sweeps 3 --spacing 3 --no-sweep-truth -o " +
                        Cohort() + " --quiet");
    ASSERT_EQ(run.code, 0) << run.output;
    run = Pectus("pipeline " + Cohort() + " --out " + (suite_ / "serial").string() + kOptions + " --report " +
                 (suite_ / "serial.json").string());
    ASSERT_EQ(run.code, 0) << run.output;
    serial_ = Outputs(suite_ / "serial");
    // Subjects beyond the imputation's core had vertices to fill (else its shared steps went untested).
    std::ifstream in(suite_ / "serial.json");
    const nlohmann::json r = nlohmann::json::parse(in);
    int late = 0;
    for (std::size_t k = 4; k < r["subjects"].size(); ++k)
      late += r["subjects"][k]["resample"].value("vertices_filled_from_cohort", 0) > 0 ? 1 : 0;
    ASSERT_GE(late, 1) << "no subject beyond the core was filled: " << r["imputation"].dump();
  }
  static void TearDownTestSuite() { fs::remove_all(suite_); }
  static std::string Cohort() { return (suite_ / "cohort").string(); }

  // The outputs in `out` are the serial run's, file for file.
  static void ExpectSerialBytes(const std::string& out, const std::string& what) {
    ASSERT_FALSE(serial_.empty());
    const std::map<std::string, std::string> files = Outputs(out);
    ASSERT_GT(serial_.size(), 20u);  // model, tables, figures, every subject's meshes
    for (const auto& [name, bytes] : serial_) {
      const auto found = files.find(name);
      ASSERT_NE(found, files.end()) << what << ": " << name << " is missing";
      EXPECT_TRUE(found->second == bytes) << what << ": " << name << " differs from the serial run's";
    }
    EXPECT_EQ(files.size(), serial_.size()) << what << ": other files than the serial run's";
    EXPECT_FALSE(fs::exists(fs::path(out) / ".pectus-work")) << what << ": the subjects' results were kept";
  }

  static inline fs::path suite_;
  static inline std::map<std::string, std::string> serial_;
};

#ifdef PECTUS_MPIEXEC
TEST_F(PipelineCluster, MpiRanksGiveTheSerialBytes) {
  for (int ranks : {1, 2, 3}) {
    const std::string out = P("ranks" + std::to_string(ranks));
    const CliRun run =
        Pectus("pipeline " + Cohort() + " --out " + out + kOptions, testing_support::MpiLauncher(ranks));
    ASSERT_EQ(run.code, 0) << ranks << " ranks: " << run.output;
    ExpectSerialBytes(out, std::to_string(ranks) + " ranks");
  }
}
#else
// Open MPI is a dependency (scripts/bootstrap installs it), as chromium is for the page: a build without
// it fails here rather than leaving the mpirun runs untested.
TEST_F(PipelineCluster, MpiIsBuiltIn) {
  FAIL() << "pectus was built without MPI: install openmpi-bin and libopenmpi-dev (scripts/bootstrap) and "
            "configure again, so that the mpirun runs are tested";
}
#endif

TEST_F(PipelineCluster, SharesGatheredGiveTheSerialBytes) {
  const std::string out = P("shares");
  auto share = [&](int k) {
    const CliRun run =
        Pectus("pipeline " + Cohort() + " --out " + out + kOptions + " --shard " + std::to_string(k) + "/3");
    ASSERT_EQ(run.code, 0) << "share " << k << ": " << run.output;
    EXPECT_FALSE(fs::exists(fs::path(out) / "model.h5")) << "a share wrote outputs";
  };
  // Share 2 alone: the gather refuses, naming what the other shares have to do.
  share(2);
  CliRun run = Pectus("pipeline " + Cohort() + " --out " + out + kOptions + " --gather");
  EXPECT_EQ(run.code, 2) << run.output;
  EXPECT_NE(run.output.find("subject_002"), std::string::npos) << run.output;   // share 3's
  EXPECT_EQ(run.output.find("subject_001,"), std::string::npos) << run.output;  // share 2's own
  EXPECT_FALSE(fs::exists(fs::path(out) / "model.h5"));
  share(3);
  share(1);
  run = Pectus("pipeline " + Cohort() + " --out " + out + kOptions + " --gather");
  ASSERT_EQ(run.code, 0) << run.output;
  ExpectSerialBytes(out, "3 shares gathered");
}

TEST_F(PipelineCluster, KilledRunResumedGivesTheSerialBytes) {
  const std::string out = P("killed");
  const fs::path records = fs::path(out) / ".pectus-work" / "surface";
  // One thread, so that subjects finish one by one; killed (SIGKILL: no clean-up) once 3 of the 6 have
  // their surface committed.
  auto count = [&] { return testing_support::CountFiles(records, ".rec"); };
  const testing_support::Killed killed = testing_support::KillWhen(
      "pipeline " + Cohort() + " --out " + out + kOptions + " --threads 1", [&] { return count() >= 3; });
  ASSERT_FALSE(killed.finished_first) << "the run finished before it could be killed half way";
  ASSERT_TRUE(killed.killed);
  EXPECT_FALSE(fs::exists(fs::path(out) / "model.h5"));
  EXPECT_GE(count(), 3u);
  const std::size_t done = count();

  const CliRun run =
      Pectus("pipeline " + Cohort() + " --out " + out + kOptions + " --resume --report " + P("resume.json"));
  ASSERT_EQ(run.code, 0) << run.output;
  ExpectSerialBytes(out, "killed with " + std::to_string(done) + " surfaces done, then resumed");
}

}  // namespace
}  // namespace pectus
