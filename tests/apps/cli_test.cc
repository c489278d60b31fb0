// The `pectus` binary as a user meets it: exit codes, reports, atomic outputs, refused overwrites.
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "registration/kdtree.h"
#include "shape/io/mesh_io.h"
#include "tests/support/command_test.h"
#include "tests/support/require_shared_data.h"

namespace pectus {
namespace {
namespace fs = std::filesystem;

using CliTest = testing_support::CommandTest;

const char* kSquare =
    "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
    "element face 2\nproperty list uchar int vertex_indices\nend_header\n"
    "0 0 0\n100 0 0\n100 100 0\n0 100 0\n3 0 1 2\n3 0 2 3\n";

TEST_F(CliTest, InfoReportsBunnyPointCount) {
  PECTUS_REQUIRE_SHARED_FILE(testing_support::kBunnyConf);
  const CliRun r = Pectus("info " + testing_support::BunnyDirectory() + "bun000.ply --report " + P("r.json"));
  ASSERT_EQ(r.code, 0) << r.output;
  std::ifstream in(P("r.json"));
  const auto j = nlohmann::json::parse(in);
  EXPECT_EQ(j["points"], 40256);
  EXPECT_EQ(j["faces"], 0);
  EXPECT_EQ(j["likely_units"], "m");
  EXPECT_EQ(j["elements"][1]["name"], "range_grid");
  EXPECT_EQ(j["elements"][1]["count"], 204800);
  EXPECT_NE(r.output.find("--input-units m"), std::string::npos) << "info should say the file is in metres";
}

TEST_F(CliTest, ConvertRoundTripsThroughEveryWrittenFormat) {
  Write("square.ply", kSquare);
  std::string previous = P("square.ply");
  for (const std::string ext : {"stl", "obj", "ply"}) {
    const std::string next = P("square_via." + ext);
    const CliRun r = Pectus("convert " + previous + " " + next + " --quiet");
    ASSERT_EQ(r.code, 0) << ext << ": " << r.output;
    previous = next;
  }
  const CliRun info = Pectus("info " + previous + " --report " + P("info.json"));
  ASSERT_EQ(info.code, 0) << info.output;
  std::ifstream in(P("info.json"));
  const auto j = nlohmann::json::parse(in);
  EXPECT_EQ(j["points"], 4);  // STL's unshared vertices were welded back
  EXPECT_EQ(j["faces"], 2);
  EXPECT_DOUBLE_EQ(j["bounds"]["max"][0].get<double>(), 100.0);
}

TEST_F(CliTest, ConvertAppliesUnitsAndTransform) {
  Write("square.ply", kSquare);
  Write("T.json", R"({"T_target_source": [[0,-1,0,10],[1,0,0,20],[0,0,1,30],[0,0,0,1]]})");
  const CliRun r = Pectus("convert " + P("square.ply") + " " + P("out.ply") +
                          " --input-units cm --transform " + P("T.json") + " --quiet");
  ASSERT_EQ(r.code, 0) << r.output;
  const CliRun info = Pectus("info " + P("out.ply") + " --report " + P("i.json"));
  std::ifstream in(P("i.json"));
  const auto j = nlohmann::json::parse(in);
  // 100 cm = 1000 mm along x, rotated onto y, then translated.
  EXPECT_NEAR(j["bounds"]["min"][0].get<double>(), -990.0, 1e-3);
  EXPECT_NEAR(j["bounds"]["max"][1].get<double>(), 1020.0, 1e-3);
  EXPECT_NEAR(j["bounds"]["min"][2].get<double>(), 30.0, 1e-3);
}

TEST_F(CliTest, BadInputExitsThreeNamesTheFileAndWritesNothing) {
  Write("broken.ply",
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
        "property float z\nend_header\n0 0 0\n1 1\n");
  const CliRun r = Pectus("convert " + P("broken.ply") + " " + P("out.ply") + " --report " + P("r.json"));
  EXPECT_EQ(r.code, 3) << r.output;
  EXPECT_NE(r.output.find("broken.ply"), std::string::npos) << r.output;
  EXPECT_EQ(CountFiles(), 1u) << "a failed run must leave no output, no report and no temporary file";
}

TEST_F(CliTest, MissingFileIsBadInput) {
  const CliRun r = Pectus("info " + P("nope.ply"));
  EXPECT_EQ(r.code, 3) << r.output;
  EXPECT_NE(r.output.find("nope.ply"), std::string::npos);
}

TEST_F(CliTest, UsageErrorsExitTwo) {
  EXPECT_EQ(Pectus("").code, 2);
  EXPECT_EQ(Pectus("frobnicate").code, 2);
  EXPECT_EQ(Pectus("convert only_one_argument.ply").code, 2);
  Write("square.ply", kSquare);
  EXPECT_EQ(Pectus("convert " + P("square.ply") + " " + P("out.unknown")).code, 2);
  EXPECT_EQ(Pectus("convert " + P("square.ply") + " " + P("o.ply") + " --input-units furlong").code, 2);
}

TEST_F(CliTest, RefusesToOverwriteItsInput) {
  Write("square.ply", kSquare);
  const auto before = fs::file_size(P("square.ply"));
  const CliRun r = Pectus("convert " + P("square.ply") + " " + dir_.string() + "/./square.ply");
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find("input"), std::string::npos);
  EXPECT_EQ(fs::file_size(P("square.ply")), before);
}

TEST_F(CliTest, HelpShowsAnExample) {
  for (const std::string command : {"info", "convert", "place"}) {
    const CliRun r = Pectus(command + " --help");
    EXPECT_EQ(r.code, 0) << command;
    EXPECT_NE(r.output.find("Example"), std::string::npos) << command << ": " << r.output;
    EXPECT_NE(r.output.find("--report"), std::string::npos) << command;
    EXPECT_NE(r.output.find("--threads"), std::string::npos) << command;
  }
}

// `pectus` runs convert, info, place and register itself and hands everything else, and any command under
// mpirun, to `pectus-full` beside it. A copy of `pectus` without `pectus-full` beside it shows which is
// which.
TEST_F(CliTest, RunsTheScanCommandsItselfAndHandsTheRestToTheFullProgram) {
  const CliRun help = Pectus("--help");
  EXPECT_EQ(help.code, 0) << help.output;
  for (const char* command : {"register", "merge", "pipeline", "serve"}) {
    EXPECT_NE(help.output.find(command), std::string::npos) << command << " missing from:\n" << help.output;
  }
  EXPECT_EQ(Pectus("merge --help").code, 0);

  const fs::path alone = dir_ / "pectus";
  fs::copy_file(PECTUS_EXECUTABLE, alone);
  auto run = [&](const std::string& args) { return testing_support::RunShell(alone.string() + " " + args); };
  for (const char* command : {"info", "convert", "place", "register"}) {
    const CliRun r = run(std::string(command) + " --help");
    EXPECT_EQ(r.code, 0) << command << ": " << r.output;
    EXPECT_NE(r.output.find("Example"), std::string::npos) << command;
  }
  for (const std::string& args :
       {std::string("merge --help"), std::string("--help"), std::string("--version")}) {
    const CliRun r = run(args);
    EXPECT_EQ(r.code, 1) << args << ": " << r.output;
    EXPECT_NE(r.output.find((dir_ / "pectus-full").string()), std::string::npos) << r.output;
  }
  // Under mpirun the full program runs even the scan commands (the ranks are its business).
  const CliRun mpi = testing_support::RunShell("OMPI_COMM_WORLD_SIZE=2 " + alone.string() + " info --help");
  EXPECT_EQ(mpi.code, 1) << mpi.output;
  EXPECT_NE(mpi.output.find("`pectus info`"), std::string::npos) << mpi.output;
}

TEST_F(CliTest, PlaceWritesOneCloudOfAllSweeps) {
  PECTUS_REQUIRE_SHARED_FILE(testing_support::kBunnyConf);
  const CliRun r =
      Pectus("place --poses " + testing_support::BunnyDirectory() + "bun.conf --input-units m -o " +
             P("bunny.ply") + " --report " + P("r.json") + " --quiet");
  ASSERT_EQ(r.code, 0) << r.output;
  std::ifstream in(P("r.json"));
  const auto j = nlohmann::json::parse(in);
  EXPECT_EQ(j["points"], 362272);
  EXPECT_EQ(j["sweeps"].size(), 10u);
  // Placed right, the merged cloud lies on Stanford's reference surface (bun_zipper.ply, in metres): the
  // median distance of its points to the reference vertices is about 0.55 mm (the vertex spacing).
  ReadOptions metres;
  metres.input_units = LengthUnit::kMetre;
  const PointCloud placed = ReadPointCloud(P("bunny.ply"));
  ASSERT_EQ(placed.size(), 362272);
  const PointCloud zipper =
      ReadPointCloud(testing_support::BunnyDirectory() + "reconstruction/bun_zipper.ply", metres);
  const KdTree3 tree(zipper.positions);
  std::vector<double> d;
  for (Eigen::Index i = 0; i < placed.size(); i += 7) {
    std::uint32_t nearest = 0;
    double d2 = 0.0;
    tree.Nearest(placed.positions.row(i).transpose(), &nearest, &d2);
    d.push_back(std::sqrt(d2));
  }
  std::nth_element(d.begin(), d.begin() + static_cast<std::ptrdiff_t>(d.size() / 2), d.end());
  EXPECT_LE(d[d.size() / 2], 0.7);
}

}  // namespace
}  // namespace pectus
