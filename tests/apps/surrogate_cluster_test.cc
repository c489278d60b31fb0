// The FE dataset (`pectus plan --dataset`, and with every patient's response basis `pectus surrogate
// build`) on a task farm (docs/cluster.md), as a user runs it: on MPI ranks (`mpirun -n 1, 2, 3`), on two
// threads, in shares gathered afterwards (`--shard K/3`, then `--gather`, which refuses while a share is
// missing), and killed half way then resumed (`--resume`). Each run's dataset is compared byte for byte
// with the serial run's, on 4 patients of the real table and the coarsest mesh (a patient in about a
// second; with its basis in 3 s, so the bases are farmed on one patient only). Two tests, so that the
// serial run is made twice, not once per case.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "tests/support/cli_run.h"
#include "tests/support/cluster_run.h"
#include "tests/support/require_shared_data.h"
#include "tests/support/scratch_dir.h"

namespace pectus {
namespace {
namespace fs = std::filesystem;

using testing_support::CliRun;
using testing_support::Pectus;

// The coarsest mesh.
const char* const kOptions = " --cell-mm 20 --quiet";
using testing_support::ReadBytes;

class SurrogateCluster : public testing_support::ScratchDirTest {
 protected:
  SurrogateCluster() : ScratchDirTest("pectus_surrogate_cluster_") {}

  // Four patients of the table and their serial dataset, for the suite's tests in this process.
  static void SetUpTestSuite() {
    if (!fs::exists(testing_support::SharedPath(testing_support::kPatientTable))) return;
    suite_ = fs::temp_directory_path() / ("pectus_surrogate_cluster_suite_" + std::to_string(getpid()));
    fs::remove_all(suite_);
    fs::create_directories(suite_);
    std::ifstream all(testing_support::SharedPath(testing_support::kPatientTable));
    std::ofstream four(Table());
    std::string line;
    for (int k = 0; k < 5 && std::getline(all, line); ++k) four << line << "\n";  // the header and 4 rows
    four.close();
    const CliRun run =
        Pectus(Build(suite_ / "serial.h5") + " --threads 1 --report " + (suite_ / "serial.json").string());
    ASSERT_EQ(run.code, 0) << run.output;
    serial_ = ReadBytes(suite_ / "serial.h5");
  }
  static void TearDownTestSuite() { fs::remove_all(suite_); }
  static std::string Table() { return (suite_ / "four.csv").string(); }
  static std::string Build(const fs::path& output) {
    return "plan --patient-table " + Table() + " --dataset " + output.string() + kOptions;
  }

  void SetUp() override {
    ScratchDirTest::SetUp();  // the test's own folder
    PECTUS_REQUIRE_SHARED_FILE(testing_support::kPatientTable);
    ASSERT_GT(serial_.size(), 4u * 100000) << "the serial dataset (4 patients) was not written";
  }

  // The dataset at `output` is the serial run's, byte for byte, and no part is left.
  static void ExpectSerialBytes(const fs::path& output, const std::string& what) {
    ASSERT_TRUE(fs::exists(output)) << what << ": no dataset";
    EXPECT_TRUE(ReadBytes(output) == serial_) << what << ": the dataset differs from the serial run's";
    const fs::path work = output.parent_path() / ("." + output.filename().string() + ".pectus-work");
    EXPECT_FALSE(fs::exists(work)) << what << ": the patients' parts were kept";
  }

  // A run killed once 2 of the 4 parts are committed, then resumed.
  void KillHalfWayAndResume();

  static inline fs::path suite_;
  static inline std::string serial_;
};

TEST_F(SurrogateCluster, ThreadsAndMpiRanksGiveTheSerialBytes) {
  // The serial run's report: every patient with its task's time, none failed.
  std::ifstream in(suite_ / "serial.json");
  const nlohmann::json r = nlohmann::json::parse(in);
  EXPECT_EQ(r["dataset"]["patients"].get<int>(), 4);
  EXPECT_EQ(r["dataset"]["results"].get<int>(), 4 * 24);
  EXPECT_TRUE(r["dataset"]["failed"].empty());
  ASSERT_EQ(r["dataset"]["per_patient"].size(), 4u);
  EXPECT_EQ(r["dataset"]["per_patient"][0]["patient"], "1");
  EXPECT_EQ(r["dataset"]["per_patient"][3]["patient"], "4");
  for (const nlohmann::json& p : r["dataset"]["per_patient"]) EXPECT_GT(p["seconds"].get<double>(), 0.0);
  // Of each task's time, what was not the part's own (the call, and in the first the generic ribcage,
  // about a millisecond at this mesh): known, and a small share of the task.
  for (const nlohmann::json& p : r["dataset"]["per_patient"]) {
    const double setup = p["setup_seconds"].get<double>();
    EXPECT_GE(setup, 0.0) << p["patient"];
    EXPECT_LT(setup, 0.1 * p["seconds"].get<double>()) << p["patient"];
  }
  EXPECT_GE(r["dataset"]["remove_parts_seconds"].get<double>(), 0.0);
  // Two threads build two patients at once; the bytes are the same.
  const fs::path threads = P("threads.h5");
  const CliRun run = Pectus(Build(threads) + " --threads 2");
  ASSERT_EQ(run.code, 0) << run.output;
  ExpectSerialBytes(threads, "2 threads");
#ifdef PECTUS_MPIEXEC
  for (int ranks : {1, 2, 3}) {
    const fs::path out = P("ranks" + std::to_string(ranks) + ".h5");
    // The FE code is leak-checked in the serial and threaded runs above; the ranks without it, 4 times
    // faster.
    const CliRun mpi = Pectus(Build(out), testing_support::MpiLauncher(ranks, /*check_leaks=*/false));
    ASSERT_EQ(mpi.code, 0) << ranks << " ranks: " << mpi.output;
    ExpectSerialBytes(out, std::to_string(ranks) + " ranks");
  }
  // With the response basis (`surrogate build`), one patient: the same bytes on 2 ranks as serially.
  std::ofstream(P("one.csv")) << "patient,haller_index,width_mm,sternal_length_mm,depth_mm,depression_mm\n"
                                 "2,4.3,283,145,153,25\n";
  const std::string bases = "surrogate build --patient-table " + P("one.csv") + kOptions + " -o ";
  const CliRun serial = Pectus(bases + P("bases_serial.h5") + " --threads 1");
  ASSERT_EQ(serial.code, 0) << serial.output;
  const CliRun two =
      Pectus(bases + P("bases_ranks.h5"), testing_support::MpiLauncher(2, /*check_leaks=*/false));
  ASSERT_EQ(two.code, 0) << two.output;
  const std::string with_bases = ReadBytes(P("bases_serial.h5"));
  EXPECT_GT(with_bases.size(), 1000000u) << "no basis in the dataset";
  EXPECT_TRUE(ReadBytes(P("bases_ranks.h5")) == with_bases) << "the dataset with bases differs on 2 ranks";
#else
  // Open MPI is a dependency (scripts/bootstrap installs it): a build without it fails here rather than
  // leaving the mpirun runs untested (as PipelineCluster.MpiIsBuiltIn).
  FAIL() << "pectus was built without MPI: install openmpi-bin and libopenmpi-dev (scripts/bootstrap) and "
            "configure again, so that the mpirun runs are tested";
#endif
}

TEST_F(SurrogateCluster, SharesGatheredAndAKilledRunResumedGiveTheSerialBytes) {
  const fs::path out = P("shares.h5");
  auto share = [&](int k) {
    const CliRun run = Pectus(Build(out) + " --threads 1 --shard " + std::to_string(k) + "/3");
    ASSERT_EQ(run.code, 0) << "share " << k << ": " << run.output;
    EXPECT_FALSE(fs::exists(out)) << "a share wrote the dataset";
  };
  // Share 2 alone (the table's 2nd patient): the gather refuses, naming the patients of the other shares.
  share(2);
  CliRun run = Pectus(Build(out) + " --gather");
  EXPECT_EQ(run.code, 2) << run.output;
  EXPECT_NE(run.output.find("patient(s) 1, 3, 4 "), std::string::npos) << run.output;
  EXPECT_FALSE(fs::exists(out));
  share(3);
  share(1);
  run = Pectus(Build(out) + " --gather");
  ASSERT_EQ(run.code, 0) << run.output;
  ExpectSerialBytes(out, "3 shares gathered");
  KillHalfWayAndResume();
}

void SurrogateCluster::KillHalfWayAndResume() {
  const fs::path out = P("killed.h5");
  const fs::path parts = fs::path(P(".killed.h5.pectus-work")) / "parts";
  // One thread, so that patients finish one by one; killed (SIGKILL: no clean-up) once 2 of the 4 have
  // their part committed.
  auto count = [&] { return testing_support::CountFiles(parts, ".h5"); };
  const testing_support::Killed killed =
      testing_support::KillWhen(Build(out) + " --threads 1", [&] { return count() >= 2; });
  ASSERT_FALSE(killed.finished_first) << "the run finished before it could be killed half way";
  ASSERT_TRUE(killed.killed);
  EXPECT_FALSE(fs::exists(out));
  const std::size_t done = count();
  EXPECT_GE(done, 2u);

  const CliRun run = Pectus(Build(out) + " --threads 1 --resume --report " + P("resume.json"));
  ASSERT_EQ(run.code, 0) << run.output;
  ExpectSerialBytes(out, "killed with " + std::to_string(done) + " parts done, then resumed");
  // The resumed run made only the patients the killed one had not.
  std::ifstream in(P("resume.json"));
  const nlohmann::json r = nlohmann::json::parse(in);
  EXPECT_EQ(r["dataset"]["patients"].get<int>(), 4);
  EXPECT_EQ(r["dataset"]["built_by_this_run"].get<std::size_t>(), 4 - done);
}

}  // namespace
}  // namespace pectus
