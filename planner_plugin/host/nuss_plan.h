// pectus planner host: a whole Nuss plan for one patient (dissertation §4.3, §5.5), step by step: the
// force to lift the sternum, the scenarios solved and scored against the average chest, the unoperated
// chest for reference, the best placement searched; then its files (meshes, pictures, HTML report).
#pragma once

#include <filesystem>
#include <functional>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "planner_plugin/host/average_chest.h"
#include "planner_plugin/host/placement_search.h"
#include "planner_plugin/host/plan_scoring.h"
#include "planner_plugin/host/planner_client.h"
#include "shape/core/report.h"

namespace pectus::planner {

/// What to plan.
struct NussPlanOptions {
  BarPlacement scenario_a;                 ///< the surgeon's placement
  std::optional<BarPlacement> scenario_b;  ///< default: 20 mm nearer the notch, same force
  bool search = true;                      ///< search the best placement
  PlacementSearchOptions search_options;
  PlanScoreOptions score;
};

/// One scored scenario.
struct PlanScenario {
  std::string name;
  PlannedCase solved;
  PlanScore score;
};

/// A plan.
struct NussPlan {
  std::vector<BarPlacement> lift_positions;             ///< 0.65, 0.75, 0.85 of the sternum and scenario A's
  std::vector<PectusPlannerForceToLift> force_to_lift;  ///< at each
  /// T_average_patient from the patient's reference landmarks (the chest without the deformity), used
  /// for every chest of the plan.
  ChestRegistrationResult registration;
  PlanScore before;                     ///< the unoperated chest against the average
  std::vector<PlanScenario> scenarios;  ///< A, B, and "best" if searched
  std::optional<PlacementSearchResult> search;
  double depression_mm = 0;     ///< the patient's sternal depression, as the generated ribcage measures it
  bool relative = true;         ///< the skin model scored (PlanScoreOptions::relative)
  double common_limit_mm = 0;   ///< colour scale of the scenarios A and B: their worst difference (Fig. 77)
  double outcome_limit_mm = 0;  ///< colour scale of the unoperated chest and the best placement
  /// Scores, lifts, force to lift, search: the figures for --report.
  nlohmann::json ToJson() const;
  /// One line: scenario A's placement and RMS difference from the average chest, and the best
  /// placement's if searched, e.g. "scenario A (0.85 L, 200 N) RMS 4.2 mm; best (0.78 L, 260 N) RMS 2.9 mm".
  std::string BriefReport() const;
};

/// One scenario of NussPlan::ToJson(): name, bar, sternal lift, the linear-range flag, the score and, if
/// `solved` (a direct solve, not the basis), the solve's figures (largest displacement, bar level, contact).
nlohmann::json ScenarioJson(const PlanScenario& scenario, double depression_mm, bool solved);

/// Makes the plan; stages are timed into `report` if not null. Throws pectus::Error.
NussPlan MakeNussPlan(const PlannerClient& planner, const AverageChest& average,
                      const NussPlanOptions& options, Report* report = nullptr);

/// Writes the plan's files into `folder`: predicted_chest_<scenario>.ply (in the average chest's frame,
/// coloured by the difference, scalar difference_mm; PredictedChest()), ribcage_A.ply and ribcage_best.ply
/// (deformed, coloured by displacement), comparison.png (A and B on one scale), before.png, ribcage.png
/// (the best placement's ribcage, or A's), search.png and
/// best.png (the unoperated chest and the best placement on one scale; if searched), report.html. Each
/// file goes through `stage(target)`, which returns the path to write it to (a transaction's staging).
/// Returns the target paths written.
std::vector<std::filesystem::path> WriteNussPlan(
    const NussPlan& plan, const PlannerClient& planner, const AverageChest& average,
    const std::string& plugin, const std::filesystem::path& folder,
    const std::function<std::filesystem::path(const std::filesystem::path&)>& stage);

}  // namespace pectus::planner
