// `pectus resample`, `pectus model` and `pectus distance` as a user meets them, on analytic chests with
// known answers: the grid lies on the surface, 30 mm holes are filled to half a millimetre, a model built
// from the grids reads back and reconstructs its own training grids, a known offset comes back as the
// distance map, and bad input exits 3 naming the file and writes nothing.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "shape/io/landmark_io.h"
#include "shape/io/mesh_io.h"
#include "tests/shape/model/analytic_chest.h"
#include "tests/support/command_test.h"

namespace pectus {
namespace {
namespace fs = std::filesystem;

nlohmann::json ReadJson(const fs::path& path) {
  std::ifstream in(path);
  return nlohmann::json::parse(in);
}

class ModelCommands : public testing_support::CommandTest {
 protected:
  // A chest with a depression of `dent_mm`, meshed at 2 mm beyond its landmark ROI, as NAME.ply and
  // NAME.mrk.json.
  testing::AnalyticChest WriteChest(const std::string& name, double dent_mm) const {
    testing::AnalyticChest chest = testing::PlacedChest();
    chest.dent_depth = dent_mm;
    WriteMesh(P(name + ".ply"), chest.Mesh(-90.0, 90.0, -30.0, 210.0, 2.0));
    WriteLandmarks(P(name + ".mrk.json"), chest.Landmarks());
    return chest;
  }
};

TEST_F(ModelCommands, ResampledGridLiesOnTheSurfaceAndHolesAreFilledToHalfAMillimetre) {
  const testing::AnalyticChest chest = WriteChest("chest", 15.0);
  CliRun run = Pectus("resample " + P("chest.ply") + " --landmarks " + P("chest.mrk.json") + " -o " +
                      P("grid.ply") + " --grid 21x41 --report " + P("r.json") + " --quiet");
  ASSERT_EQ(run.code, 0) << run.output;
  const TriangleMesh grid = ReadMesh(P("grid.ply"));
  ASSERT_EQ(grid.num_vertices(), 21 * 41);
  const Similarity3 T_chest_world = chest.T_world_chest.Inverse();
  double worst = 0.0;
  for (Eigen::Index k = 0; k < grid.num_vertices(); ++k) {
    const Eigen::Vector3d p = T_chest_world * Eigen::Vector3d(grid.vertices.positions.row(k).transpose());
    worst = std::max(worst, std::abs(p.z() - chest.f(p.x(), -p.y())));
  }
  EXPECT_LT(worst, 0.05) << "largest height of a grid vertex off the analytic chest, mm";
  EXPECT_EQ(ReadJson(P("r.json"))["shape_vector_size"].get<int>(), 3 * 21 * 41);

  run = Pectus("resample " + P("chest.ply") + " --landmarks " + P("chest.mrk.json") +
               " --validate --error-png " + P("holes.png") + " --report " + P("v.json") + " --quiet");
  ASSERT_EQ(run.code, 0) << run.output;
  const nlohmann::json h = ReadJson(P("v.json"))["hole_fill"];
  EXPECT_EQ(h["regions"].size(), 3u);
  EXPECT_DOUBLE_EQ(h["regions"][0]["radius_mm"].get<double>(), 15.0);
  EXPECT_GT(h["vertices_in_regions"].get<int>(), 100);
  EXPECT_LT(h["max_error_in_regions_mm"].get<double>(), 0.5);
  EXPECT_TRUE(fs::exists(P("holes.png")));
}

TEST_F(ModelCommands, ModelFileRoundTripsAndReconstructsItsTrainingGrids) {
  std::string grids;
  for (int i = 0; i < 4; ++i) {
    const std::string name = "s" + std::to_string(i);
    WriteChest(name, 6.0 * i);
    const CliRun run = Pectus("resample " + P(name + ".ply") + " --landmarks " + P(name + ".mrk.json") +
                              " -o " + P(name + "_grid.ply") + " --grid 11x21 --quiet");
    ASSERT_EQ(run.code, 0) << run.output;
    grids += " " + P(name + "_grid.ply");
  }
  CliRun run = Pectus("model build" + grids + " -o " + P("m.h5") + " --eigen " + P("eigen.csv") +
                      " --variance-png " + P("variance.png") + " --report " + P("build.json") + " --quiet");
  ASSERT_EQ(run.code, 0) << run.output;
  const nlohmann::json built = ReadJson(P("build.json"));
  EXPECT_EQ(built["subjects"].get<int>(), 4);
  EXPECT_EQ(built["modes"].get<int>(), 3);

  run = Pectus("model info " + P("m.h5") + " --report " + P("info.json") + " --quiet");
  ASSERT_EQ(run.code, 0) << run.output;
  const nlohmann::json info = ReadJson(P("info.json"));
  EXPECT_EQ(info["points"].get<int>(), 11 * 21);
  EXPECT_EQ(info["modes"].get<int>(), 3);
  EXPECT_NEAR(info["total_variance_mm2"].get<double>(), built["total_variance_mm2"].get<double>(),
              1e-9 * built["total_variance_mm2"].get<double>());
  // Only the depth of the depression varies, so one mode holds (nearly) all the variance.
  EXPECT_GT(info["variance"][0]["cumulative"].get<double>(), 0.99) << info.dump();

  // A training grid is in the model's span: its reconstruction is exact up to float32 storage.
  run =
      Pectus("model project " + P("m.h5") + " " + P("s2_grid.ply") + " --report " + P("p.json") + " --quiet");
  ASSERT_EQ(run.code, 0) << run.output;
  EXPECT_LT(ReadJson(P("p.json"))["reconstruction_max_mm"].get<double>(), 1e-3);

  // A grid of another size is bad input: exit 3, the file named, no reconstruction written.
  WriteChest("other", 3.0);
  run = Pectus("resample " + P("other.ply") + " --landmarks " + P("other.mrk.json") + " -o " +
               P("other_grid.ply") + " --grid 9x21 --quiet");
  ASSERT_EQ(run.code, 0) << run.output;
  run =
      Pectus("model project " + P("m.h5") + " " + P("other_grid.ply") + " --reconstruction " + P("rec.ply"));
  EXPECT_EQ(run.code, 3) << run.output;
  EXPECT_NE(run.output.find("other_grid.ply"), std::string::npos) << run.output;
  EXPECT_FALSE(fs::exists(P("rec.ply")));
}

TEST_F(ModelCommands, DistanceMapOfAnOffsetSurfaceIsTheOffset) {
  // A flat chest and the same moved 3 mm anterior: every signed distance is +3 mm, every nearest-vertex
  // distance 3 mm (the meshes share their vertex layout).
  testing::AnalyticChest flat;
  flat.radius = 1e12;
  flat.slope = 0.0;
  flat.dent_depth = 0.0;
  const TriangleMesh reference = flat.Mesh(-60.0, 60.0, 0.0, 120.0, 3.0);
  TriangleMesh moved = reference;
  moved.vertices.positions.col(2).array() += 3.0;
  WriteMesh(P("reference.ply"), reference);
  WriteMesh(P("moved.ply"), moved);
  for (const std::string kind : {"signed", "nearest"}) {
    const CliRun run =
        Pectus("distance " + P("moved.ply") + " " + P("reference.ply") + " --kind " + kind + " --png " +
               P(kind + ".png") + " --histogram " + P(kind + "_hist.png") + " --ply " + P(kind + ".ply") +
               " --range 5 --report " + P(kind + ".json") + " --quiet");
    ASSERT_EQ(run.code, 0) << run.output;
    const nlohmann::json s = ReadJson(P(kind + ".json"))["statistics"];
    EXPECT_NEAR(s["min_mm"].get<double>(), 3.0, 1e-6) << kind;
    EXPECT_NEAR(s["max_mm"].get<double>(), 3.0, 1e-6) << kind;
    EXPECT_NEAR(s["rms_mm"].get<double>(), 3.0, 1e-6) << kind;
    EXPECT_EQ(s["count"].get<int>(), moved.num_vertices());
    const TriangleMesh coloured = ReadMesh(P(kind + ".ply"));
    ASSERT_TRUE(coloured.vertices.scalars.count("distance_mm")) << kind;
    EXPECT_NEAR(coloured.vertices.scalars.at("distance_mm").mean(), 3.0, 1e-5) << kind;
    EXPECT_TRUE(fs::exists(P(kind + ".png")) && fs::exists(P(kind + "_hist.png"))) << kind;
  }
  // The reference is missing: exit 3 naming it, and nothing written.
  const CliRun run =
      Pectus("distance " + P("moved.ply") + " " + P("missing.ply") + " --ply " + P("never.ply"));
  EXPECT_EQ(run.code, 3) << run.output;
  EXPECT_NE(run.output.find("missing.ply"), std::string::npos) << run.output;
  EXPECT_FALSE(fs::exists(P("never.ply")));
}

}  // namespace
}  // namespace pectus
