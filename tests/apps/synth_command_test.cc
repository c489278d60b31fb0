// `pectus synth` as a user meets it: the files of each mode, byte-identical output per seed whatever the
// thread count, exit codes for bad options and a bad table, and nothing left behind by a failed run.
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "datasets/scan_writer.h"
#include "tests/support/command_test.h"
#include "tests/support/require_shared_data.h"

namespace pectus::datasets {
namespace {
namespace fs = std::filesystem;

std::string Slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

using SynthCommand = testing_support::CommandTest;

const std::string kSmall = " --sweeps 3 --spacing 5 --truth-spacing 10 -q";

TEST_F(SynthCommand, CohortIsByteIdenticalPerSeedWhateverTheThreads) {
  ASSERT_EQ(
      Pectus("synth cohort --subjects 3 --seed 4 --grid 11x21 --modes 2 --threads 1 --out " + P("a") + kSmall)
          .code,
      0);
  ASSERT_EQ(Pectus("synth cohort --subjects 3 --seed 4 --grid 11x21 --modes 2 --threads 2 --out " + P("b") +
                   kSmall + " --report " + P("r.json"))
                .code,
            0);
  int files = 0;
  for (const fs::directory_entry& e : fs::recursive_directory_iterator(dir_ / "a")) {
    if (!e.is_regular_file()) continue;
    ++files;
    const fs::path other = dir_ / "b" / fs::relative(e.path(), dir_ / "a");
    ASSERT_TRUE(fs::exists(other)) << other;
    EXPECT_EQ(Slurp(e.path()), Slurp(other)) << e.path();
  }
  // 3 subjects x (3 sweeps, 3 sweep truths, landmarks, 2 meshes, poses .json and .conf, true landmarks,
  // subject)
  // + population (population.json, mean, 2 modes, mean landmarks) + synth.json.
  EXPECT_EQ(files, 3 * 13 + 5 + 1);
  const nlohmann::json report = nlohmann::json::parse(Slurp(dir_ / "r.json"));
  EXPECT_EQ(report["subjects"], 3);
  EXPECT_TRUE(report["timings_s"].contains("scan_and_write"));
  // A different seed gives different data.
  ASSERT_EQ(Pectus("synth cohort --subjects 1 --seed 5 --grid 11x21 --modes 2 --out " + P("c") + kSmall).code,
            0);
  EXPECT_NE(Slurp(dir_ / "a/subject_000/sweep_00.ply"), Slurp(dir_ / "c/subject_000/sweep_00.ply"));
}

TEST_F(SynthCommand, SubjectPairAndPatientWriteTheirFolders) {
  PECTUS_REQUIRE_SHARED_FILE(testing_support::kPatientTable);
  ASSERT_EQ(
      Pectus("synth subject --seed 3 --pectus-depth 30 --pectus-type cup --out " + P("s") + kSmall).code, 0);
  const SubjectFolder s = ReadSubjectFolder(dir_ / "s");
  EXPECT_EQ(s.sweeps.size(), 3u);
  EXPECT_EQ(s.subject.parameters.pectus.depth_mm, 30.0);
  EXPECT_EQ(s.subject.parameters.pectus.type, PectusType::kCup);
  ASSERT_EQ(Pectus("synth pair --seed 3 --years 2 --out " + P("p") + kSmall).code, 0);
  const SubjectFolder pre = ReadSubjectFolder(dir_ / "p/pre"), post = ReadSubjectFolder(dir_ / "p/post");
  EXPECT_NEAR(post.subject.parameters.growth.y(), 1.05 * 1.05, 1e-12);
  EXPECT_EQ(LinearPart(pre.subject.parameters), LinearPart(post.subject.parameters));
  ASSERT_EQ(Pectus("synth patient --row 57 --row 3 --table " + testing_support::PatientTablePath() +
                   " --out " + P("t") + kSmall)
                .code,
            0);
  const SubjectFolder t = ReadSubjectFolder(dir_ / "t/patient_57");
  EXPECT_EQ(t.subject.extra["patient_row"]["depression_mm"], 21.0);
  EXPECT_TRUE(fs::exists(dir_ / "t/patient_3/sweep_00.ply"));
}

// The widened scanner from the command line: a spiral of random points whose tracker error moves each
// sweep's points by exactly 3 mm RMS about the sensor; poses.json records the options and, per sweep, the
// displacement at the skin; the sweep files carry no range-image scalars. A bad pattern is a usage error.
TEST_F(SynthCommand, WidenedScannerOptionsReachTheFiles) {
  ASSERT_EQ(Pectus("synth subject --seed 3 --pattern spiral --sampling random --tracker-pivot lever "
                   "--tracker-lever 250 --tracker-skin 3 --out " +
                   P("w") + kSmall)
                .code,
            0);
  const nlohmann::json poses = nlohmann::json::parse(Slurp(dir_ / "w/truth/poses.json"));
  EXPECT_EQ(poses["scan_options"]["pattern"], "spiral");
  EXPECT_EQ(poses["scan_options"]["sampling"], "random");
  EXPECT_EQ(poses["scan_options"]["tracker_pivot"], "lever");
  EXPECT_EQ(poses["scan_options"]["tracker_lever_mm"], 250.0);
  ASSERT_EQ(poses["sweeps"].size(), 3u);
  for (const nlohmann::json& sweep : poses["sweeps"])
    EXPECT_NEAR(sweep["tracker_skin_rms_mm"].get<double>(), 3.0, 1e-6);
  EXPECT_EQ(Slurp(dir_ / "w/sweep_00.ply").find("property float line"), std::string::npos);
  // The original scanner's files name none of the new options.
  ASSERT_EQ(Pectus("synth subject --seed 3 --out " + P("o") + kSmall).code, 0);
  EXPECT_FALSE(nlohmann::json::parse(Slurp(dir_ / "o/truth/poses.json"))["scan_options"].contains("pattern"));
  EXPECT_EQ(Pectus("synth subject --pattern zigzag --out " + P("x") + kSmall).code, 2);
}

TEST_F(SynthCommand, HelpShowsAWorkedExample) {
  const CliRun run = Pectus("synth cohort --help");
  EXPECT_EQ(run.code, 0);
  EXPECT_NE(run.output.find("pectus synth cohort --subjects 11 --seed 7"), std::string::npos);
}

TEST_F(SynthCommand, BadOptionsAndBadTableFailCleanly) {
  PECTUS_REQUIRE_SHARED_FILE(testing_support::kPatientTable);
  EXPECT_EQ(Pectus("synth cohort --subjects 2 --noise -1 --out " + P("x") + kSmall).code, 2);
  EXPECT_EQ(Pectus("synth subject --pectus-type funnel --out " + P("x") + kSmall).code, 2);
  EXPECT_EQ(Pectus("synth patient --out " + P("x") + kSmall).code, 2);  // no --row
  std::ofstream(dir_ / "bad.csv") << "patient,haller_index,width_mm\n1,3,250\n";
  const CliRun bad = Pectus("synth patient --row 1 --table " + P("bad.csv") + " --out " + P("x") + kSmall);
  EXPECT_EQ(bad.code, 3);
  EXPECT_NE(bad.output.find("bad.csv"), std::string::npos);
  // A patient the table does not have: a usage error listing the patients it has.
  const CliRun absent = Pectus("synth patient --row 99 --table " + testing_support::PatientTablePath() +
                               " --out " + P("x") + kSmall);
  EXPECT_EQ(absent.code, 2);
  EXPECT_NE(absent.output.find("patient 99 is not in"), std::string::npos) << absent.output;
  EXPECT_NE(absent.output.find("(patients 1-62)"), std::string::npos) << absent.output;
  EXPECT_FALSE(fs::exists(dir_ / "x" / "synth.json"));
  EXPECT_FALSE(fs::exists(dir_ / "x" / "sweep_00.ply"));
}

}  // namespace
}  // namespace pectus::datasets
