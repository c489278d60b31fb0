// The whole plan through the real plugin. The average chest is the patient's own predicted chest under a
// known bar placement, moved to another frame and scaled: the search must find that placement again, at
// a difference of zero, and the scenarios must score worse.
#include "planner_plugin/host/nuss_plan.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "shape/model/shape_model.h"
#include "shape/model/statismo_io.h"
#include "tests/support/require_shared_data.h"

namespace pectus::planner {
namespace {
namespace fs = std::filesystem;

TEST(NussPlan, TheSearchFindsTheKnownPlacementOfAnAverageChestMadeFromItAndTheFilesAreWritten) {
  PECTUS_REQUIRE_SHARED_FILE(testing_support::kPatientTable);
  const fs::path dir = fs::temp_directory_path() / ("pectus_nuss_plan_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const PlannerPlugin plugin = PlannerPlugin::Load(PECTUS_PLANNER_PLUGIN_PATH);
  PectusPlannerOptions options = PluginDefaultOptions(plugin);
  options.rib_cell_length_mm = 10;
  options.sternum_cells_along = 28;
  options.skin_rows = 32;
  options.skin_columns = 48;
  PlannerClient planner(plugin, ReadPlannerPatient(plugin, testing_support::PatientTablePath(), "57"),
                        options);

  // The "average chest": patient 57 under a bar at 0.78 of the sternum lifting the sternum by 80 % of its
  // depression, in the pectus scan frame (x across, y up, z anterior), 10 % larger, written as a statismo
  // model with its landmarks.
  const double lift_force = planner.ForceToLift({{0.78, false, 1}}).front().force_n;
  const BarPlacement truth{0.78, false, 0.8 * lift_force};
  const PlannedCase target = planner.Solve({truth}, false).front();
  Similarity3 T;
  T.scale = 1.1;
  T.rotation << 1, 0, 0, 0, 0, 1, 0, -1, 0;  // LPS to the scan frame
  T.translation = Eigen::Vector3d(5, 1200, -40);
  Points3 x = target.skin;
  for (Eigen::Index i = 0; i < x.rows(); ++i)
    x.row(i) = (T * Eigen::Vector3d(x.row(i).transpose())).transpose();
  nlohmann::json info;
  // Its landmarks: the patient's reference landmarks (the chest without the deformity) in that frame.
  for (const char* label : {"sternal_notch", "manubrium_centre", "xiphoid"}) {
    const Eigen::Vector3d p = T * planner.reference_landmarks().Position(label, "reference");
    info["landmarks"][label] = {p.x(), p.y(), p.z()};
  }
  Eigen::MatrixXd shapes(2, x.size());
  shapes.row(0) = Eigen::Map<const Eigen::VectorXd>(x.data(), x.size()).transpose().array() + 0.25;
  shapes.row(1) = Eigen::Map<const Eigen::VectorXd>(x.data(), x.size()).transpose().array() - 0.25;
  ShapeModel model = BuildShapeModel(shapes);
  model.faces = planner.skin().faces;
  WriteStatismoModel(dir / "average.h5", model, info);
  const AverageChest average = LoadAverageChest(dir / "average.h5");

  // The modelled skin is what the average chest was made of: the search must find the placement again.
  NussPlanOptions plan_options;
  plan_options.score.relative = false;
  plan_options.scenario_a = {0.85, false, 1700};
  plan_options.search_options.positions = 6;
  plan_options.search_options.forces = 11;
  Report report;
  const NussPlan plan = MakeNussPlan(planner, average, plan_options, &report);

  // The search recovers the placement (float32 model file: a difference of micrometres remains).
  ASSERT_TRUE(plan.search.has_value());
  EXPECT_NEAR(plan.search->best.position, truth.position, 0.01);
  EXPECT_NEAR(plan.search->best.force_n, truth.force_n, 0.03 * truth.force_n);
  EXPECT_LT(plan.search->best_objective_mm, 0.05) << plan.search->ToJson().dump();
  EXPECT_NEAR(plan.registration.T_target_source.scale, 1.1, 1e-6);
  EXPECT_LT(plan.registration.landmark_rms_mm, 1e-4);
  // Scenario B is 20 mm nearer the notch; both are worse than the best, the unoperated chest worse still.
  ASSERT_EQ(plan.scenarios.size(), 3u);
  EXPECT_TRUE(plan.scenarios[1].solved.bar.position_in_mm);
  EXPECT_NEAR(plan.scenarios[1].solved.bar.position, 0.85 * planner.measurements().sternal_length_mm - 20,
              1e-9);
  EXPECT_GT(plan.scenarios[0].score.roi.rms, 10 * plan.search->best_objective_mm);
  EXPECT_GT(plan.before.roi.rms, 1.0);
  EXPECT_GE(plan.common_limit_mm, plan.scenarios[0].score.roi.max_abs);
  // Force to lift at 0.65, 0.75, 0.85 and at A; the deeper the bar, the less force (the lower sternum is
  // the deepest).
  ASSERT_EQ(plan.force_to_lift.size(), 4u);
  EXPECT_GT(plan.force_to_lift[0].force_n, plan.force_to_lift[2].force_n);
  EXPECT_DOUBLE_EQ(plan.force_to_lift[3].force_n, plan.force_to_lift[2].force_n);
  EXPECT_TRUE(plan.ToJson().contains("search"));
  // The truth lies inside the space searched: the best is not on an edge.
  EXPECT_EQ(plan.search->position_at_edge, 0);
  EXPECT_FALSE(plan.search->force_at_limit);
  EXPECT_EQ(SearchEdgeNote(*plan.search), "");
  // 1700 N lifts the sternum far beyond twice its depression: both scenarios are flagged, the best is not.
  const nlohmann::json json = plan.ToJson();
  EXPECT_DOUBLE_EQ(json["linear_range_lift_mm"].get<double>(), 2 * planner.measurements().depression_mm);
  EXPECT_TRUE(json["scenarios"][0]["beyond_linear_range"].get<bool>());
  EXPECT_TRUE(json["scenarios"][1]["beyond_linear_range"].get<bool>());
  EXPECT_FALSE(json["scenarios"][2]["beyond_linear_range"].get<bool>());

  // A space that stops short of the truth (positions to 0.7, forces to half the true one): the best is
  // the corner nearest the truth, and the search says it lies on both edges.
  PlacementSearchOptions short_options = plan_options.search_options;
  short_options.position_to = 0.7;
  short_options.force_max_n = 0.5 * truth.force_n;
  const PlacementSearchResult edge =
      SearchBestPlacement(planner, average, plan.registration, plan_options.score, short_options);
  EXPECT_EQ(edge.best.position, edge.positions.back()) << edge.ToJson().dump();
  EXPECT_NEAR(edge.best.position, 0.7, 1e-12);
  EXPECT_EQ(edge.position_at_edge, 1);
  EXPECT_TRUE(edge.force_at_limit);
  EXPECT_DOUBLE_EQ(edge.best.force_n, 0.5 * truth.force_n);
  const std::string note = SearchEdgeNote(edge);
  EXPECT_NE(note.find("caudal end of the positions searched (0.5-0.7 L)"), std::string::npos) << note;
  EXPECT_NE(note.find("largest searched"), std::string::npos) << note;
  EXPECT_EQ(edge.ToJson()["best_position_at_edge"], "last");

  // The same search on the exact response basis: every grid score within 0.01 mm of the direct solves'
  // (the basis holds 0.001 mm), the same best placement, no solve.
  EXPECT_FALSE(plan.search->from_basis);
  const PectusPlannerBasisSummary basis = planner.BuildBasis();
  EXPECT_GT(basis.rank, 0);
  const PlacementSearchResult fast = SearchBestPlacement(planner, average, plan.registration,
                                                         plan_options.score, plan_options.search_options);
  EXPECT_TRUE(fast.from_basis);
  ASSERT_EQ(fast.objective_mm.rows(), plan.search->objective_mm.rows());
  EXPECT_LT((fast.objective_mm - plan.search->objective_mm).cwiseAbs().maxCoeff(), 0.01);
  EXPECT_NEAR(fast.best_objective_mm, plan.search->best_objective_mm, 0.01);
  EXPECT_NEAR(fast.best.position, plan.search->best.position, 1e-3);
  EXPECT_NEAR(fast.best.force_n, plan.search->best.force_n, 1e-3 * plan.search->best.force_n);
  EXPECT_EQ(fast.evaluations, plan.search->evaluations);

  // The files.
  const auto written = WriteNussPlan(plan, planner, average, plugin.description(), dir / "plan",
                                     [](const fs::path& target_path) {
                                       fs::create_directories(target_path.parent_path());
                                       return target_path;
                                     });
  for (const char* name : {"predicted_chest_A.ply", "predicted_chest_B.ply", "predicted_chest_best.ply",
                           "ribcage_A.ply", "ribcage_best.ply", "comparison.png", "before.png", "ribcage.png",
                           "search.png", "best.png", "report.html"}) {
    EXPECT_TRUE(fs::exists(dir / "plan" / name)) << name;
    EXPECT_GT(fs::file_size(dir / "plan" / name), 100u) << name;
  }
  EXPECT_EQ(written.size(), 11u);
  std::ifstream html(dir / "plan" / "report.html");
  std::stringstream text;
  text << html.rdbuf();
  for (const char* expected :
       {"patient 57", "Best bar placement", "comparison.png", "search.png", "Weber", "beyond the model"}) {
    EXPECT_NE(text.str().find(expected), std::string::npos) << expected;
  }
  fs::remove_all(dir);
}

}  // namespace
}  // namespace pectus::planner
