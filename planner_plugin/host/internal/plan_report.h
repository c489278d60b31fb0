// pectus planner host: the plan's HTML report: the patient's ribcage against its CT measurements, the
// force to lift the sternum, the scenarios side by side with their scores against the average chest,
// and the best placement found. Pictures are PNG files beside the report, referenced by name.
#pragma once

#include <string>
#include <vector>

#include "planner_plugin/api/planner_api.h"
#include "planner_plugin/host/placement_search.h"
#include "planner_plugin/host/plan_scoring.h"
#include "planner_plugin/host/planner_client.h"

namespace pectus::planner {

/// One scenario of the report.
struct ReportScenario {
  std::string name;  ///< e.g. "A"
  BarPlacement bar;
  PectusPlannerCaseResult figures{};
  DistanceStats roi, central;         ///< the scores
  double sternum_lift_needed_mm = 0;  ///< the patient's depression (for "lift / depression")
};

/// Everything the report shows.
struct PlanReportInput {
  PectusPlannerPatient patient{};
  PectusPlannerMeasurements measured{};
  PectusPlannerOptions options{};
  std::string plugin;                                   ///< the plugin's description and path
  std::string average_chest;                            ///< model file and landmark source
  std::vector<BarPlacement> lift_positions;             ///< with...
  std::vector<PectusPlannerForceToLift> force_to_lift;  ///< ...the force to lift at each
  DistanceStats before;                                 ///< the unoperated chest against the average
  std::vector<ReportScenario> scenarios;
  double common_limit_mm = 0;                     ///< the colour scale of the scenarios A and B
  double outcome_limit_mm = 0;                    ///< ... of the unoperated chest and the best placement
  bool relative = true;                           ///< the relative skin model (else the modelled skin)
  const PlacementSearchResult* search = nullptr;  ///< or none
  /// Picture file names (relative to the report): the comparison, the unoperated chest, the ribcage,
  /// the search map, the best placement.
  std::string comparison_png, before_png, ribcage_png, search_png, best_png;
};

/// The report as one self-contained HTML page (pictures by relative file name).
std::string PlanReportHtml(const PlanReportInput& input);

}  // namespace pectus::planner
