#include "planner_plugin/host/nuss_plan.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "planner_plugin/host/internal/plan_figures.h"
#include "planner_plugin/host/internal/plan_report.h"
#include "shape/core/atomic_file.h"
#include "shape/core/error.h"
#include "shape/io/mesh_io.h"
#include "shape/render/colormap.h"

namespace pectus::planner {
namespace fs = std::filesystem;

namespace {

double MaxAbsFinite(const Eigen::VectorXd& v) {
  double m = 0;
  for (Eigen::Index i = 0; i < v.size(); ++i) {
    if (std::isfinite(v(i))) m = std::max(m, std::abs(v(i)));
  }
  return m;
}

// The stage's timer if there is a report.
std::optional<Report::StageTimer> Time(Report* report, const std::string& name) {
  if (report == nullptr) return std::nullopt;
  return std::optional<Report::StageTimer>(std::in_place, report, name);
}

nlohmann::json BarJson(const BarPlacement& bar) {
  return {{"position", bar.position}, {"position_in_mm", bar.position_in_mm}, {"force_n", bar.force_n}};
}

}  // namespace

nlohmann::json ScenarioJson(const PlanScenario& s, double depression_mm, bool solved) {
  const double lift = s.solved.figures.sternum_lift_mm;
  nlohmann::json j = {{"name", s.name},
                      {"bar", BarJson(s.solved.bar)},
                      {"sternum_lift_mm", lift},
                      {"beyond_linear_range", lift > LinearRangeLiftMm(depression_mm)}};
  if (solved) {
    j["max_displacement_mm"] = s.solved.figures.max_displacement_mm;
    j["bar_level_z_mm"] = s.solved.figures.bar_level_z_mm;
    j["contact_area_mm2"] = s.solved.figures.contact_area_mm2;
  }
  j["score"] = s.score.ToJson();
  return j;
}

std::string NussPlan::BriefReport() const {
  if (scenarios.empty()) return "no scenario";
  const PlanScenario& a = scenarios.front();
  char text[300];
  std::snprintf(text, sizeof(text), "scenario A (%s) RMS %.1f mm", a.solved.bar.Name().c_str(),
                a.score.roi.rms);
  std::string line = text;
  if (search) {
    const PlanScenario& best = scenarios.back();
    std::snprintf(text, sizeof(text), "; best (%s) RMS %.1f mm", best.solved.bar.Name().c_str(),
                  best.score.roi.rms);
    line += text;
  }
  return line;
}

nlohmann::json NussPlan::ToJson() const {
  nlohmann::json j;
  for (std::size_t i = 0; i < force_to_lift.size(); ++i) {
    nlohmann::json f = BarJson(lift_positions[i]);
    f.erase("force_n");
    f["lift_per_newton_mm"] = force_to_lift[i].lift_per_newton_mm;
    f["force_to_lift_n"] = force_to_lift[i].force_n;
    j["force_to_lift"].push_back(f);
  }
  const Eigen::Matrix4d M = registration.T_target_source.Matrix();
  std::vector<std::vector<double>> rows(4, std::vector<double>(4));
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) rows[r][c] = M(r, c);
  }
  j["registration"] = {{"scale", registration.T_target_source.scale},
                       {"landmarks_used", registration.used},
                       {"landmark_rms_mm", registration.landmark_rms_mm},
                       {"T_average_patient", rows}};
  j["before"] = before.ToJson();
  j["depression_mm"] = depression_mm;
  j["linear_range_lift_mm"] = LinearRangeLiftMm(depression_mm);
  for (const PlanScenario& s : scenarios) j["scenarios"].push_back(ScenarioJson(s, depression_mm, true));
  if (search) j["search"] = search->ToJson();
  j["common_scale_mm"] = common_limit_mm;
  return j;
}

NussPlan MakeNussPlan(const PlannerClient& planner, const AverageChest& average,
                      const NussPlanOptions& options, Report* report) {
  NussPlan plan;
  plan.depression_mm = planner.measurements().depression_mm;
  const double length = planner.measurements().sternal_length_mm;
  const BarPlacement& a = options.scenario_a;
  const double a_mm = a.position_in_mm ? a.position : a.position * length;
  const BarPlacement b =
      options.scenario_b ? *options.scenario_b : BarPlacement{std::max(0.0, a_mm - 20.0), true, a.force_n};
  {
    // Step 1: the force that lifts the sternum by the depression, at the dissertation's positions and at A.
    auto t = Time(report, "force_to_lift");
    plan.lift_positions = {
        {0.65, false, 1}, {0.75, false, 1}, {0.85, false, 1}, {a.position, a.position_in_mm, 1}};
    plan.force_to_lift = planner.ForceToLift(plan.lift_positions);
  }
  {
    // Step 2: the unoperated chest and the scenarios, solved on the one factorisation and scored.
    auto t = Time(report, "scenarios");
    plan.registration = RegisterChestByLandmarks(
        planner.reference_landmarks(), AnteriorDirection(planner.skin(), "patient skin"), average.landmarks,
        AnteriorDirection(average.mesh, "average chest"), options.score.registration);
    plan.relative = options.score.relative;
    const Points3& reference = planner.reference_skin();
    plan.before = ScorePlan(planner.skin(), reference, plan.registration, average, options.score);
    const std::vector<PlannedCase> solved = planner.Solve({a, b});
    for (std::size_t i = 0; i < solved.size(); ++i) {
      TriangleMesh skin = planner.skin();
      skin.vertices.positions = solved[i].skin;
      plan.scenarios.push_back({i == 0 ? "A" : "B", solved[i],
                                ScorePlan(skin, reference, plan.registration, average, options.score)});
    }
  }
  if (options.search) {
    // Step 3: the best placement, then its full solution.
    auto t = Time(report, "placement_search");
    plan.search =
        SearchBestPlacement(planner, average, plan.registration, options.score, options.search_options);
    const PlannedCase best = planner.Solve({plan.search->best}).front();
    TriangleMesh skin = planner.skin();
    skin.vertices.positions = best.skin;
    plan.scenarios.push_back(
        {"best", best, ScorePlan(skin, planner.reference_skin(), plan.registration, average, options.score)});
  }
  // Colour scales in whole mm: the scenarios A and B share the worst of theirs (dissertation Fig. 77);
  // the unoperated chest and the best placement share theirs.
  auto worst = [](const PlanScore& s) {
    return std::max(MaxAbsFinite(s.difference_mm), MaxAbsFinite(s.predicted_distance_mm));
  };
  plan.common_limit_mm =
      std::ceil(std::max({1.0, worst(plan.scenarios[0].score), worst(plan.scenarios[1].score)}));
  plan.outcome_limit_mm = std::ceil(std::max(1.0, worst(plan.before)));
  if (plan.search)
    plan.outcome_limit_mm = std::max(plan.outcome_limit_mm, std::ceil(worst(plan.scenarios[2].score)));
  return plan;
}

std::vector<fs::path> WriteNussPlan(const NussPlan& plan, const PlannerClient& planner,
                                    const AverageChest& average, const std::string& plugin,
                                    const fs::path& folder,
                                    const std::function<fs::path(const fs::path&)>& stage) {
  std::vector<fs::path> written;
  auto target = [&](const std::string& name) {
    written.push_back(folder / name);
    return stage(folder / name);
  };
  const double limit = plan.common_limit_mm;
  // Meshes: the predicted chests in the average chest's frame, coloured by their difference.
  auto chest_of = [&](const PlanScore& score, Eigen::VectorXd* values) {
    return PredictedChest(score, average, planner.skin(), plan.relative, values);
  };
  for (const PlanScenario& s : plan.scenarios) {
    Eigen::VectorXd values;
    TriangleMesh chest = chest_of(s.score, &values);
    chest.vertices.colors = DifferenceColors(values, s.name == "best" ? plan.outcome_limit_mm : limit);
    chest.vertices.scalars["difference_mm"] = values;
    WriteMesh(target("predicted_chest_" + s.name + ".ply"), chest);
  }
  // The deformed ribcage of the surgeon's placement (A) and of the best one, coloured by displacement.
  auto ribcage_of = [&](const PlanScenario& s, Eigen::VectorXd* moved) {
    TriangleMesh bone = planner.bone();
    bone.vertices.positions = s.solved.bone;
    *moved = (s.solved.bone - planner.bone().vertices.positions).rowwise().norm();
    bone.vertices.colors =
        render::MapColors(*moved, 0.0, std::max(1.0, moved->maxCoeff()), render::Colormap::kViridis);
    bone.vertices.scalars["displacement_mm"] = *moved;
    return bone;
  };
  Eigen::VectorXd moved;
  for (const PlanScenario& s : plan.scenarios) {
    if (s.name != "B") WriteMesh(target("ribcage_" + s.name + ".ply"), ribcage_of(s, &moved));
  }

  // Pictures, all difference maps on one scale and in one frame.
  const render::View view = AverageChestFrontView(average);
  auto picture = [&](const PlanScore& score, double scale, const std::string& title) {
    Eigen::VectorXd values;
    const TriangleMesh chest = chest_of(score, &values);
    char text[200];
    std::snprintf(text, sizeof(text), "%s, RMS %.1f mm", title.c_str(), score.roi.rms);
    return RenderDifference(chest, values, scale, view, text);
  };
  const std::string label = "predicted - average, mm";
  render::WritePng(
      SideBySide({picture(plan.scenarios[0].score, limit, "A: " + plan.scenarios[0].solved.bar.Name()),
                  picture(plan.scenarios[1].score, limit, "B: " + plan.scenarios[1].solved.bar.Name())},
                 limit, label),
      target("comparison.png"));
  const render::Image before = picture(plan.before, plan.outcome_limit_mm, "before the operation");
  render::WritePng(SideBySide({before}, plan.outcome_limit_mm, label), target("before.png"));
  // The ribcage picture: the best placement (or A), framing the ribcage before and after.
  const PlanScenario& shown = plan.scenarios.back();
  const TriangleMesh bone = ribcage_of(shown, &moved);
  Bounds3 frame = ComputeBounds(planner.bone().vertices.positions);
  const Bounds3 after = ComputeBounds(bone.vertices.positions);
  frame.min = frame.min.cwiseMin(after.min);
  frame.max = frame.max.cwiseMax(after.max);
  render::WritePng(
      RenderRibcageDisplacement(bone, moved, std::max(1.0, moved.maxCoeff()), PatientObliqueView(frame),
                                "ribcage, " + shown.name + ": " + shown.solved.bar.Name()),
      target("ribcage.png"));
  PlanReportInput input;
  input.patient = planner.patient();
  input.options = planner.options();
  if (plan.search) {
    render::WritePng(RenderSearchMap(*plan.search, "RMS difference to the average chest"),
                     target("search.png"));
    render::WritePng(SideBySide({before, picture(plan.scenarios[2].score, plan.outcome_limit_mm,
                                                 "best: " + plan.scenarios[2].solved.bar.Name())},
                                plan.outcome_limit_mm, label),
                     target("best.png"));
    input.search = &*plan.search;
    input.search_png = "search.png";
    input.best_png = "best.png";
  }
  // The report.
  input.measured = planner.measurements();
  input.plugin = plugin;
  input.average_chest = average.source + ", landmarks: " + average.landmark_source;
  input.lift_positions = plan.lift_positions;
  input.force_to_lift = plan.force_to_lift;
  input.before = plan.before.roi;
  for (const PlanScenario& s : plan.scenarios) {
    if (s.name == "best") continue;
    input.scenarios.push_back({s.name, s.solved.bar, s.solved.figures, s.score.roi, s.score.central_roi,
                               planner.measurements().depression_mm});
  }
  input.common_limit_mm = limit;
  input.outcome_limit_mm = plan.outcome_limit_mm;
  input.relative = plan.relative;
  input.comparison_png = "comparison.png";
  input.before_png = "before.png";
  input.ribcage_png = "ribcage.png";
  WriteFileAtomically(target("report.html"), PlanReportHtml(input));
  return written;
}

}  // namespace pectus::planner
