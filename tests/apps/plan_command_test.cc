// `pectus plan` as a user runs it (apps/commands/plan_command.cc): the example for patient 57,
// on a coarse mesh (10 mm rib cells, which folded rib 10 before the cartilages kept their own cells) and a
// small search, against an analytic average chest written as a statismo model.
// Known answers: scenario B is 20 mm nearer the notch than A; the model is linear, so A's sternal lift
// is its force times the depression over the force to lift; the best placement scores better than both
// scenarios and than the unoperated chest; every file the report shows exists. Bad input: exit codes.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <regex>
#include <sstream>

#include "tests/planner_plugin/host/analytic_chest.h"
#include "tests/planner_plugin/host/average_model_file.h"
#include "tests/support/cli_run.h"
#include "tests/support/require_shared_data.h"

namespace pectus::planner {
namespace {
namespace fs = std::filesystem;
using testing_support::Pectus;

class PlanCommandTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("pectus_plan_command_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
    // The average chest: an analytic grid (landmarks by the grid's convention), two shapes 1 mm apart.
    testing::WriteAverageModel(dir_ / "average.h5", testing::AnalyticChestGrid(31, 41));
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string Path(const std::string& name) const { return "'" + (dir_ / name).string() + "'"; }
  fs::path dir_;
};

TEST_F(PlanCommandTest, Patient57GivesTwoScenariosTheBestPlacementAndAnHtmlReportWithPictures) {
  PECTUS_REQUIRE_SHARED_FILE(testing_support::kPatientTable);
  const auto run =
      Pectus("plan --patient-table '" + testing_support::PatientTablePath() + "' --patient 57 --model " +
             Path("average.h5") + " --bar-position 0.85 --force 1700 --out " + Path("plan57") + " --report " +
             Path("r.json") +
             " --cell-mm 10 --search-positions 3 --search-forces 4 --search-refinements 3 --threads 1");
  ASSERT_EQ(run.code, 0) << run.output;
  // 1700 N (the example) is far beyond the force to lift for this model: the command says so,
  // and the report flags both scenarios.
  EXPECT_NE(run.output.find("far outside its range"), std::string::npos) << run.output;
  // The summary gives the scores in tenths of a millimetre.
  const std::regex summary(
      "plan for patient 57: scenario A \\(0\\.85 L, 1700 N\\) RMS [0-9]+\\.[0-9] mm; best");
  EXPECT_TRUE(std::regex_search(run.output, summary)) << run.output;
  std::ifstream in(dir_ / "r.json");
  const nlohmann::json r = nlohmann::json::parse(in);
  ASSERT_EQ(r["scenarios"].size(), 3u);
  const auto& a = r["scenarios"][0];
  const auto& b = r["scenarios"][1];
  const auto& best = r["scenarios"][2];
  EXPECT_EQ(a["name"], "A");
  EXPECT_EQ(b["name"], "B");
  EXPECT_EQ(best["name"], "best");
  // B: 20 mm nearer the notch, in mm along the sternum (0.85 of patient 57's 168 mm is 142.8 mm).
  const double length = r["ribcage"]["model"]["sternal_length_mm"];
  EXPECT_TRUE(b["bar"]["position_in_mm"].get<bool>());
  EXPECT_NEAR(b["bar"]["position"].get<double>(), 0.85 * length - 20.0, 1e-6);
  // Linear model: lift(A) = 1700 N x depression / force to lift at 0.85.
  const double depression = r["ribcage"]["model"]["depression_mm"];
  double force_to_lift = 0;
  for (const auto& f : r["force_to_lift"]) {
    if (f["position"] == 0.85 && !f["position_in_mm"].get<bool>()) force_to_lift = f["force_to_lift_n"];
  }
  ASSERT_GT(force_to_lift, 0.0);
  EXPECT_NEAR(a["sternum_lift_mm"].get<double>(), 1700.0 * depression / force_to_lift, 1e-6 * 1700.0);
  EXPECT_TRUE(a["beyond_linear_range"].get<bool>());
  EXPECT_FALSE(best["beyond_linear_range"].get<bool>());
  // The default cartilage is the calibrated one (80 MPa), and the report says so.
  EXPECT_EQ(r["materials"]["costal_cartilage"]["youngs_modulus_mpa"].get<double>(), 80.0);
  EXPECT_EQ(r["materials"]["sternum"]["youngs_modulus_mpa"].get<double>(), 11500.0);
  // The search's placement is better than both scenarios and than leaving the chest as it is.
  const double best_rms = best["score"]["rms_mm"];
  EXPECT_LT(best_rms, a["score"]["rms_mm"].get<double>());
  EXPECT_LT(best_rms, b["score"]["rms_mm"].get<double>());
  EXPECT_LT(best_rms, r["before"]["rms_mm"].get<double>());
  // The search scored it from the response basis, the scenario from a direct solve: equal to the basis'
  // tolerance (0.003 mm; in practice 1e-8).
  EXPECT_TRUE(r["search"]["from_basis"].get<bool>());
  EXPECT_GT(r["response_basis"]["rank"].get<int>(), 0);
  EXPECT_NEAR(best_rms, r["search"]["best"]["objective_mm"].get<double>(), 1e-3);
  // The report shows the comparison, the search and the pictures, and every picture exists.
  std::ifstream html(dir_ / "plan57" / "report.html");
  std::stringstream text;
  text << html.rdbuf();
  for (const char* png : {"comparison.png", "search.png", "best.png", "ribcage.png"}) {
    EXPECT_NE(text.str().find(png), std::string::npos) << png;
    EXPECT_GT(fs::file_size(dir_ / "plan57" / png), 1000u) << png;
  }
}

TEST_F(PlanCommandTest, BadInputAndUsageHaveTheirExitCodesAndWriteNothing) {
  PECTUS_REQUIRE_SHARED_FILE(testing_support::kPatientTable);
  const std::string common = "plan --patient-table '" + testing_support::PatientTablePath() + "' --model " +
                             Path("average.h5") + " --out " + Path("out") + " --cell-mm 8 --no-search";
  auto run = Pectus(common + " --patient nobody");  // an argument naming no patient of the table: usage
  EXPECT_EQ(run.code, 2) << run.output;
  EXPECT_NE(run.output.find("nobody"), std::string::npos) << run.output;
  {
    std::ofstream table(dir_ / "deep.csv");  // a depression beyond the modeller's 0-60 mm: bad input
    table << "patient,width_mm,sternal_length_mm,depth_mm,depression_mm\n1,250,150,140,70\n";
  }
  run = Pectus("plan --patient-table " + Path("deep.csv") + " --patient 1 --model " + Path("average.h5") +
               " --out " + Path("out") + " --no-search");
  EXPECT_EQ(run.code, 3) << run.output;
  EXPECT_NE(run.output.find("deep.csv:2: column 'depression_mm': 70 is out of range: must be 0 to 60"),
            std::string::npos)
      << run.output;
  run = Pectus(common + " --patient 57 --bar-position 1.5");
  EXPECT_EQ(run.code, 2) << run.output;
  run = Pectus("plan --patient-table '" + testing_support::PatientTablePath() + "' --model " +
               Path("average.h5") + " --out " + Path("out") +
               " --no-search --patient 57 --cell-mm 25");  // a mesh cell length outside what is tested
  EXPECT_EQ(run.code, 2) << run.output;
  EXPECT_NE(run.output.find("rib_cell_length_mm must be 2 to 20 mm"), std::string::npos) << run.output;
  run = Pectus("plan --patient-table '" + testing_support::PatientTablePath() + "' --patient 57 --out " +
               Path("out"));  // no --model
  EXPECT_EQ(run.code, 2) << run.output;
  EXPECT_FALSE(fs::exists(dir_ / "out"));
}

}  // namespace
}  // namespace pectus::planner
