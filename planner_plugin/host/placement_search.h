// pectus planner host: the bar position and force that bring the predicted chest closest to the average
// chest (the planner's question, dissertation §4.3: "choose the most optimal location for the bar").
// The model is linear, so one solve per position gives every force at that position.
#pragma once

#include <Eigen/Core>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "planner_plugin/host/plan_scoring.h"
#include "planner_plugin/host/planner_client.h"
#include "shape/core/timings.h"

namespace pectus::planner {

/// The search space and its resolution.
struct PlacementSearchOptions {
  /// Bar positions searched: fractions of the sternal length from the notch. Defaults 0.5 to 0.95 in
  /// 10 steps: the sternal body (which ends at about 0.90, the xiphisternal joint), where the bar goes,
  /// and the upper half of the xiphoid. Not beyond 0.95: the bar would sit on the xiphoid's tip.
  double position_from = 0.5, position_to = 0.95;
  int positions = 10;
  /// Forces searched: `forces` steps up to the largest force worth trying: force_max_n (N), or, if less,
  /// `lift_limit` times the force that lifts the sternum by its depression at the position where that
  /// takes most force (a larger push only over-corrects). Defaults 3000 N, 31 steps, 2.
  double force_max_n = 3000;
  int forces = 31;
  double lift_limit = 2.0;
  /// After the grid, golden-section searches refine the best cell: for a position, the force between
  /// the grid's neighbours of its best force; then the position between the grid's neighbours of the
  /// best position, each position at its best force (the valley of good placements runs diagonally:
  /// a bar nearer the notch needs more force). Iterations of each golden-section search (each shrinks
  /// the bracket by 0.618). Default 16.
  int golden_iterations = 16;
  /// What is minimised: the RMS difference over the region of interest ("rms") or over its central part
  /// ("central_rms"). Default "rms".
  std::string objective = "rms";
  bool IsValid(std::string* why) const;
};

/// What the search found.
struct PlacementSearchResult {
  std::vector<double> positions;  ///< the grid's positions (fractions)
  std::vector<double> forces_n;   ///< the grid's forces
  double force_limit_n = 0;       ///< the largest force searched (see PlacementSearchOptions)
  Eigen::MatrixXd objective_mm;   ///< #positions by #forces: the objective on the grid
  BarPlacement best;              ///< after refinement
  double best_objective_mm = 0;
  /// Where the best lies on the edge of the space searched, where the objective still falls towards the
  /// edge: -1 at position_from, +1 at position_to, 0 inside; and whether its force is the largest
  /// searched (force_limit_n). SearchEdgeNote() says what that means.
  int position_at_edge = 0;
  bool force_at_limit = false;
  PlanScore best_score;
  int evaluations = 0;      ///< chests scored
  int solves = 0;           ///< positions solved by the plugin (from its basis if it has one)
  bool from_basis = false;  ///< the unit responses came from the plugin's exact response basis
  /// Wall time, s: "search" (the grid and its refinement), within it "unit_responses" (the plugin's
  /// responses to 1 N) and "scoring" (the chests scored against the average).
  Timings timings_s;
  nlohmann::json ToJson() const;
};

/// A sentence for the user when the best placement lies on the edge of the space searched (empty if it
/// does not): which edge, and why the search does not go beyond it.
std::string SearchEdgeNote(const PlacementSearchResult& result);

/// Searches the bar placement minimising the objective. Throws Error(kUsage) for invalid options.
/// Every candidate is scored in the frame of `registration` (see ScorePlan).
PlacementSearchResult SearchBestPlacement(const PlannerClient& planner, const AverageChest& average,
                                          const ChestRegistrationResult& registration,
                                          const PlanScoreOptions& score_options,
                                          const PlacementSearchOptions& options = {});

}  // namespace pectus::planner
