// The emulator's training set: a set written and read back is the same to the bit; a damaged, truncated
// or foreign file fails with an error naming it; invalid options are refused before any FE work.
#include "planner_plugin/surrogate/emulator_training_set.h"

#include <gtest/gtest.h>

#include <fstream>

#include "shape/core/error.h"
#include "tests/support/scratch_dir.h"

namespace pectus::planner {
namespace {

class EmulatorTrainingSetTest : public testing_support::ScratchDirTest {
 protected:
  EmulatorTrainingSetTest() : ScratchDirTest("pectus_emulator_training_set_") {}

  // 3 patients, 2 positions, a 2 x 3 skin grid, 4 bone vertices, 4 boundary nodes, random values.
  static EmulatorTrainingSet Small() {
    EmulatorTrainingSet set;
    set.patients = {"1", "22", "333"};
    set.positions = Eigen::Vector2d(0.65, 0.85);
    set.ct_inputs = Eigen::MatrixXd::Random(3, 6);
    set.model_inputs = Eigen::MatrixXd::Random(3, 8);
    set.lift_per_newton = Eigen::MatrixXd::Random(3, 2);
    set.skin_rows = 2;
    set.skin_columns = 3;
    set.skin = {Eigen::MatrixXd::Random(3, 18), Eigen::MatrixXd::Random(3, 18)};
    set.bone = {Eigen::MatrixXd::Random(3, 12), Eigen::MatrixXd::Random(3, 12)};
    set.skin_anchor_generic_mm = Eigen::MatrixXd::Random(3, 18);
    set.boundary_nodes = {5, 7, 11, 13};
    set.boundary = {Eigen::MatrixXd::Random(3, 12), Eigen::MatrixXd::Random(3, 12)};
    for (int i = 0; i < 3; ++i) {
      Eigen::SparseMatrix<double, Eigen::RowMajor> ties(6, 4);
      for (int j = 0; j < 6; ++j) {
        ties.insert(j, (i + j) % 4) = 0.25 * (i + 1);
        ties.insert(j, (i + j + 1) % 4) = 1.0 - 0.25 * (i + 1);
      }
      set.skin_ties.push_back(ties);
      Eigen::SparseMatrix<double, Eigen::RowMajor> lift(1, 12);
      lift.insert(0, 3 * i + 1) = 0.5;
      lift.insert(0, 3 * i + 4) = 0.5;
      set.lift_ties.push_back(lift);
    }
    return set;
  }
};

TEST_F(EmulatorTrainingSetTest, SaveThenLoadGivesTheSameSet) {
  const EmulatorTrainingSet set = Small();
  SaveEmulatorTrainingSet(set, P("set.bin"));
  const EmulatorTrainingSet back = LoadEmulatorTrainingSet(P("set.bin"));
  EXPECT_EQ(back.patients, set.patients);
  EXPECT_EQ(back.skin_rows, 2);
  EXPECT_EQ(back.skin_columns, 3);
  EXPECT_EQ(back.positions, set.positions);
  EXPECT_EQ(back.ct_inputs, set.ct_inputs);
  EXPECT_EQ(back.model_inputs, set.model_inputs);
  EXPECT_EQ(back.lift_per_newton, set.lift_per_newton);
  ASSERT_EQ(back.skin.size(), 2u);
  ASSERT_EQ(back.bone.size(), 2u);
  for (int k = 0; k < 2; ++k) {
    EXPECT_EQ(back.skin[k], set.skin[k]);
    EXPECT_EQ(back.bone[k], set.bone[k]);
  }
  EXPECT_EQ(back.skin_anchor_generic_mm, set.skin_anchor_generic_mm);
  EXPECT_EQ(back.boundary_nodes, set.boundary_nodes);
  ASSERT_EQ(back.boundary.size(), 2u);
  for (int k = 0; k < 2; ++k) EXPECT_EQ(back.boundary[k], set.boundary[k]);
  ASSERT_EQ(back.skin_ties.size(), 3u);
  ASSERT_EQ(back.lift_ties.size(), 3u);
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(Eigen::MatrixXd(back.skin_ties[i]), Eigen::MatrixXd(set.skin_ties[i]));
    EXPECT_EQ(Eigen::MatrixXd(back.lift_ties[i]), Eigen::MatrixXd(set.lift_ties[i]));
  }
}

TEST_F(EmulatorTrainingSetTest, DamagedFilesFailNamingTheFile) {
  SaveEmulatorTrainingSet(Small(), P("set.bin"));
  std::ifstream in(P("set.bin"), std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), {});
  auto message = [&](const std::string& name, const std::string& content) -> std::string {
    std::ofstream(P(name), std::ios::binary) << content;
    try {
      LoadEmulatorTrainingSet(P(name));
    } catch (const Error& e) {
      return e.what();
    }
    return "no throw";
  };
  std::string m = message("short.bin", bytes.substr(0, bytes.size() - 100));
  EXPECT_NE(m.find("short.bin"), std::string::npos) << m;
  EXPECT_NE(m.find("truncated"), std::string::npos) << m;
  m = message("foreign.bin", "not a training set at all, just text");
  EXPECT_NE(m.find("foreign.bin"), std::string::npos) << m;
  EXPECT_NE(m.find("magic"), std::string::npos) << m;
  m = message("longer.bin", bytes + "x");
  EXPECT_NE(m.find("damaged"), std::string::npos) << m;
  EXPECT_THROW(LoadEmulatorTrainingSet(P("missing.bin")), Error);
  EmulatorTrainingSet wrong = Small();
  wrong.skin[1] = Eigen::MatrixXd::Zero(3, 17);
  try {
    SaveEmulatorTrainingSet(wrong, P("wrong.bin"));
    ADD_FAILURE() << "no throw";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("skin response"), std::string::npos) << e.what();
  }
}

TEST_F(EmulatorTrainingSetTest, InvalidOptionsAreRefused) {
  EmulatorTrainingSetOptions options;
  options.positions = {0.5, 1.2};
  std::string why;
  EXPECT_FALSE(options.IsValid(&why));
  EXPECT_NE(why.find("(0, 1)"), std::string::npos) << why;
  EXPECT_THROW(BuildEmulatorTrainingSet({}, options), Error);
}

}  // namespace
}  // namespace pectus::planner
