#include "planner_plugin/host/average_chest.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>

#include "shape/core/error.h"
#include "tests/planner_plugin/host/analytic_chest.h"
#include "tests/planner_plugin/host/average_model_file.h"

namespace pectus::planner {
namespace {
namespace fs = std::filesystem;

using testing::WriteAverageModel;

class AverageChestTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("pectus_average_chest_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
};

TEST_F(AverageChestTest, AResampledGridGivesItsLandmarksByConvention) {
  const TriangleMesh grid = testing::AnalyticChestGrid(31, 41);
  WriteAverageModel(dir_ / "average.h5", grid);
  const AverageChest average = LoadAverageChest(dir_ / "average.h5");
  EXPECT_EQ(average.grid_columns, 31);
  EXPECT_EQ(average.grid_rows, 41);
  // The mean of the two shapes is the grid (float32 in the file).
  EXPECT_LT((average.mesh.vertices.positions - grid.vertices.positions).cwiseAbs().maxCoeff(), 1e-4);
  // Notch at the top row's middle (x = 0, y = 0), xiphoid at the bottom row's (y = -170), on the surface.
  EXPECT_LT((average.landmarks.Position("sternal_notch", "t") - Eigen::Vector3d(0, 0, 110)).norm(), 1e-4);
  EXPECT_LT((average.landmarks.Position("xiphoid", "t") - Eigen::Vector3d(0, -170, 110)).norm(), 1e-4);
}

TEST_F(AverageChestTest, LandmarksInTheModelFileOrAFileComeFirst) {
  const TriangleMesh grid = testing::AnalyticChestGrid(31, 41);
  const nlohmann::json info = {
      {"landmarks", {{"sternal_notch", {1, 2, 3}}, {"xiphoid", {4, 5, 6}}, {"manubrium_centre", {7, 8, 9}}}}};
  WriteAverageModel(dir_ / "with_landmarks.h5", grid, info);
  const AverageChest average = LoadAverageChest(dir_ / "with_landmarks.h5");
  EXPECT_EQ(average.landmarks.Position("manubrium_centre", "t"), Eigen::Vector3d(7, 8, 9));
  // A mesh that is not a grid and has no landmarks cannot be used.
  TriangleMesh shuffled = grid;
  shuffled.faces.row(0) = grid.faces.row(1);
  shuffled.faces.row(1) = grid.faces.row(0);
  WriteAverageModel(dir_ / "no_landmarks.h5", shuffled);
  EXPECT_FALSE(DetectGrid(shuffled, nullptr, nullptr));
  try {
    LoadAverageChest(dir_ / "no_landmarks.h5");
    ADD_FAILURE() << "expected an error";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::kBadInput);
    EXPECT_NE(std::string(e.what()).find("--model-landmarks"), std::string::npos) << e.what();
  }
  // A file that is not a model names itself.
  EXPECT_THROW(LoadAverageChest(dir_ / "missing.h5"), Error);
}

}  // namespace
}  // namespace pectus::planner
