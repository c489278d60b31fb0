// `pectus synth cohort` and `pectus register --cohort` on a task farm (docs/cluster.md), as a user runs
// them: on MPI ranks (`mpirun -n 2, 3`), in shares gathered afterwards, and killed half way then
// resumed. Each run's outputs are compared byte for byte with the serial run's.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <string>

#include "tests/support/cli_run.h"
#include "tests/support/cluster_run.h"
#include "tests/support/scratch_dir.h"

namespace pectus {
namespace {
namespace fs = std::filesystem;

using testing_support::CliRun;
using testing_support::FilesUnder;
using testing_support::Pectus;

// Five subjects of three coarse sweeps: seconds under the sanitizers.
// The groupwise rounds of those torsos keep moving by more than the 0.05 mm at which they would settle,
// so each run does all 20 rounds (the scans are then reported unsettled: --keep-going writes the summary).
const char* const kGroupwise = " --groupwise --keep-going";
const char* const kSynth =
    "synth cohort --subjects 5 --seed 4 --sweeps 3 --spacing 3 --no-sweep-truth --truth-spacing 3 --quiet";

class CohortCluster : public testing_support::ScratchDirTest {
 protected:
  CohortCluster() : ScratchDirTest("pectus_cohort_cluster_") {}

  // The serial runs, once for the suite's tests in this process: the synthetic cohort, and its subjects'
  // true surfaces with their landmarks as a folder of scans for `register --cohort`.
  static void SetUpTestSuite() {
    suite_ = fs::temp_directory_path() / ("pectus_cohort_cluster_suite_" + std::to_string(getpid()));
    fs::remove_all(suite_);
    fs::create_directories(suite_ / "scans");
    CliRun run = Pectus(std::string(kSynth) + " -o " + (suite_ / "cohort").string());
    ASSERT_EQ(run.code, 0) << run.output;
    synth_ = FilesUnder(suite_ / "cohort");
    for (int i = 0; i < 5; ++i) {
      const std::string name = "subject_00" + std::to_string(i);
      const fs::path subject = suite_ / "cohort" / name;
      fs::copy_file(subject / "truth" / "surface.ply", suite_ / "scans" / (name + ".ply"));
      fs::copy_file(subject / "landmarks.mrk.json", suite_ / "scans" / (name + ".mrk.json"));
    }
    run = Pectus(RegisterArgs((suite_ / "to_reference").string()));
    ASSERT_EQ(run.code, 0) << run.output;
    to_reference_ = FilesUnder(suite_ / "to_reference");
  }
  // The serial groupwise run (20 rounds: seconds), made by the tests that compare with it.
  static const std::map<std::string, std::string>& Groupwise() {
    if (groupwise_.empty()) {
      const CliRun run = Pectus(RegisterArgs((suite_ / "groupwise").string()) + kGroupwise);
      EXPECT_EQ(run.code, 0) << run.output;
      groupwise_ = FilesUnder(suite_ / "groupwise");
    }
    return groupwise_;
  }
  static void TearDownTestSuite() { fs::remove_all(suite_); }
  // Different people's whole torsos: registered on the chest about the landmarks, with their scale.
  static std::string RegisterArgs(const std::string& out) {
    return "register --cohort " + (suite_ / "scans").string() + " -o " + out +
           " --scale --patch-radius 80 --quiet";
  }

  static void ExpectSame(const std::map<std::string, std::string>& serial, const fs::path& out,
                         const std::string& what) {
    ASSERT_FALSE(serial.empty());
    testing_support::ExpectSameFiles(serial, FilesUnder(out), what,
                                     [](const std::string& failure) { ADD_FAILURE() << failure; });
    EXPECT_FALSE(fs::exists(out / ".pectus-work")) << what << ": the work folder was kept";
  }

  static inline fs::path suite_;
  static inline std::map<std::string, std::string> synth_, to_reference_, groupwise_;
};

TEST_F(CohortCluster, SerialRunsWriteWhatAUserExpects) {
  // The cohort: every subject's sweeps and truth, the population; the registration: a transform per
  // scan and the summary, every scan registered.
  EXPECT_EQ(synth_.count("subject_004/sweep_02.ply"), 1u);
  EXPECT_EQ(synth_.count("population/mean.ply"), 1u);
  EXPECT_EQ(synth_.count("synth.json"), 1u);
  EXPECT_EQ(to_reference_.size(), 6u);
  ASSERT_EQ(to_reference_.count("summary.json"), 1u);
  const nlohmann::json summary = nlohmann::json::parse(to_reference_.at("summary.json"));
  ASSERT_EQ(summary["scans"].size(), 5u);
  EXPECT_TRUE(summary["all_succeeded"].get<bool>()) << summary.dump(1);
}

#ifdef PECTUS_MPIEXEC
TEST_F(CohortCluster, MpiRanksGiveTheSerialBytes) {
  for (int ranks : {2, 3}) {
    const std::string r = std::to_string(ranks);
    CliRun run = Pectus(std::string(kSynth) + " -o " + P("synth" + r), testing_support::MpiLauncher(ranks));
    ASSERT_EQ(run.code, 0) << ranks << " ranks: " << run.output;
    ExpectSame(synth_, P("synth" + r), "synth cohort on " + r + " ranks");
    for (const char* mode : {"", kGroupwise}) {
      if (*mode && ranks == 2) continue;  // 20 rounds: on 3 ranks only, to keep the test short
      const std::string out = P(std::string(*mode ? "groupwise" : "to_reference") + r);
      run = Pectus(RegisterArgs(out) + mode, testing_support::MpiLauncher(ranks));
      ASSERT_EQ(run.code, 0) << ranks << " ranks" << mode << ": " << run.output;
      ExpectSame(*mode ? Groupwise() : to_reference_, out,
                 "register --cohort" + std::string(mode) + " on " + r + " ranks");
    }
  }
}
#endif

TEST_F(CohortCluster, SharesGatheredGiveTheSerialBytes) {
  const std::string out = P("shares");
  auto share = [&](int k) {
    const CliRun run = Pectus(std::string(kSynth) + " -o " + out + " --shard " + std::to_string(k) + "/3");
    ASSERT_EQ(run.code, 0) << "share " << k << ": " << run.output;
    EXPECT_FALSE(fs::exists(fs::path(out) / "synth.json")) << "a share wrote outputs";
  };
  share(3);
  CliRun run = Pectus(std::string(kSynth) + " -o " + out + " --gather");
  EXPECT_EQ(run.code, 2) << run.output;  // shares 1 and 2 are missing: named
  EXPECT_NE(run.output.find("subject_000"), std::string::npos) << run.output;
  EXPECT_EQ(run.output.find("subject_002"), std::string::npos) << run.output;  // share 3's own
  share(1);
  share(2);
  run = Pectus(std::string(kSynth) + " -o " + out + " --gather");
  ASSERT_EQ(run.code, 0) << run.output;
  ExpectSame(synth_, out, "synth cohort in 3 shares gathered");

  // register --cohort (to the reference) in 3 shares; groupwise shares are refused with the reason.
  const std::string aligned = P("aligned_shares");
  for (int k : {2, 1, 3}) {
    run = Pectus(RegisterArgs(aligned) + " --shard " + std::to_string(k) + "/3");
    ASSERT_EQ(run.code, 0) << "share " << k << ": " << run.output;
    EXPECT_FALSE(fs::exists(fs::path(aligned) / "summary.json")) << "a share wrote outputs";
    if (k == 2) {
      run = Pectus(RegisterArgs(aligned) + " --gather");
      EXPECT_EQ(run.code, 2) << run.output;
      EXPECT_NE(run.output.find("subject_003"), std::string::npos) << run.output;  // share 1's
    }
  }
  run = Pectus(RegisterArgs(aligned) + " --gather");
  ASSERT_EQ(run.code, 0) << run.output;
  ExpectSame(to_reference_, aligned, "register --cohort in 3 shares gathered");
  run = Pectus(RegisterArgs(P("groupwise_share")) + kGroupwise + " --shard 1/2");
  EXPECT_EQ(run.code, 2) << run.output;
  EXPECT_NE(run.output.find("groupwise rounds need"), std::string::npos) << run.output;
}

TEST_F(CohortCluster, KilledRunsResumedGiveTheSerialBytes) {
  // synth: one thread, killed (SIGKILL) once 2 of the 5 subjects are committed.
  const std::string synth = P("synth_killed");
  const fs::path records = fs::path(synth) / ".pectus-work" / "synth-done";
  testing_support::Killed killed =
      testing_support::KillWhen(std::string(kSynth) + " -o " + synth + " --threads 1",
                                [&] { return testing_support::CountFiles(records, ".json") >= 2; });
  ASSERT_FALSE(killed.finished_first) << "synth finished before it could be killed half way";
  ASSERT_TRUE(killed.killed);
  EXPECT_FALSE(fs::exists(fs::path(synth) / "synth.json"));
  CliRun run = Pectus(std::string(kSynth) + " -o " + synth + " --resume");
  ASSERT_EQ(run.code, 0) << run.output;
  ExpectSame(synth_, synth, "synth cohort killed and resumed");

  // register --groupwise: killed in its second round (every scan's first-round fit committed), then
  // resumed on 2 threads.
  const std::string out = P("groupwise_killed");
  const fs::path work = fs::path(out) / ".pectus-work";
  killed = testing_support::KillWhen(RegisterArgs(out) + kGroupwise + " --threads 1", [&] {
    return testing_support::CountFiles(work / "groupwise-2", ".fit") >= 1;
  });
  ASSERT_FALSE(killed.finished_first) << "register finished before it could be killed half way";
  ASSERT_TRUE(killed.killed);
  EXPECT_FALSE(fs::exists(fs::path(out) / "summary.json"));
  EXPECT_EQ(testing_support::CountFiles(work / "groupwise-1", ".fit"), 5u);
  run = Pectus(RegisterArgs(out) + kGroupwise + " --resume");
  ASSERT_EQ(run.code, 0) << run.output;
  ExpectSame(Groupwise(), out, "register --cohort --groupwise killed and resumed");
}

}  // namespace
}  // namespace pectus
