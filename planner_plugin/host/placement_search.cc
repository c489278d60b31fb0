#include "planner_plugin/host/placement_search.h"

#include <atomic>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <optional>

#include "shape/core/error.h"

namespace pectus::planner {

bool PlacementSearchOptions::IsValid(std::string* why) const {
  auto fail = [&](const std::string& reason) {
    if (why) *why = reason;
    return false;
  };
  if (!(position_from > 0 && position_to <= 1 && position_from < position_to)) {
    return fail("positions must satisfy 0 < from < to <= 1 (fractions of the sternal length)");
  }
  if (positions < 2 || forces < 2) return fail("at least 2 positions and 2 forces");
  if (!(force_max_n > 0 && force_max_n <= 20000)) return fail("force_max_n must be in (0, 20000] N");
  if (!(lift_limit >= 1 && lift_limit <= 100)) return fail("lift_limit must be 1 to 100");
  if (golden_iterations < 0 || golden_iterations > 60) return fail("golden_iterations must be 0 to 60");
  if (objective != "rms" && objective != "central_rms")
    return fail("objective must be 'rms' or 'central_rms'");
  return true;
}

nlohmann::json PlacementSearchResult::ToJson() const {
  nlohmann::json grid = nlohmann::json::array();
  for (Eigen::Index i = 0; i < objective_mm.rows(); ++i) {
    std::vector<double> row(static_cast<std::size_t>(objective_mm.cols()));
    for (Eigen::Index j = 0; j < objective_mm.cols(); ++j)
      row[static_cast<std::size_t>(j)] = objective_mm(i, j);
    grid.push_back(row);
  }
  return {
      {"best", {{"position", best.position}, {"force_n", best.force_n}, {"objective_mm", best_objective_mm}}},
      {"best_position_at_edge", position_at_edge < 0   ? "first"
                                : position_at_edge > 0 ? "last"
                                                       : "no"},
      {"best_force_at_limit", force_at_limit},
      {"edge_note", SearchEdgeNote(*this)},
      {"best_score", best_score.ToJson()},
      {"positions", positions},
      {"forces_n", forces_n},
      {"force_limit_n", force_limit_n},
      {"objective_mm", grid},
      {"evaluations", evaluations},
      {"solves", solves},
      {"from_basis", from_basis},
      {"timings_s", timings_s.ToJson()}};
}

std::string SearchEdgeNote(const PlacementSearchResult& result) {
  if (result.positions.empty()) return "";
  char text[600];
  std::string note;
  if (result.position_at_edge != 0) {
    const bool last = result.position_at_edge > 0;
    std::snprintf(
        text, sizeof(text),
        "The best position, %.3g L, is the %s end of the positions searched (%.3g-%.3g L): the RMS "
        "still falls towards it. %s",
        result.best.position, last ? "caudal" : "cranial", result.positions.front(), result.positions.back(),
        last && result.positions.back() >= 0.95
            ? "The search goes no lower: the sternal body ends at about 0.90 L, and below 0.95 L the "
              "bar would sit on the tip of the xiphoid."
            : "A wider range may place it better (--search-from/--search-to).");
    note = text;
  }
  if (result.force_at_limit) {
    std::snprintf(text, sizeof(text),
                  "%sThe best force, %.0f N, is the largest searched: more would lift the sternum beyond "
                  "the linear model's range (twice the depression) or above --search-max-force.",
                  note.empty() ? "" : " ", result.best.force_n);
    note += text;
  }
  return note;
}

namespace {

// The skin at one position, per newton (the model is linear).
struct UnitResponse {
  Points3 skin0, skin_per_n;
  double lift_per_n = 0;
  PlanScorer::LinearSkin linear;  // the same, projected for the scorer
};

// Golden-section search of f over [lo, hi]; improves (*x, *value) if it finds a lower value.
template <typename F>
void GoldenSection(double lo, double hi, int iterations, F&& f, double* x, double* value) {
  constexpr double kInvPhi = 0.6180339887498949;
  double a = lo, b = hi;
  double c = b - kInvPhi * (b - a), d = a + kInvPhi * (b - a);
  double fc = f(c), fd = f(d);
  for (int k = 0; k < iterations; ++k) {
    if (fc < fd) {
      b = d;
      d = c;
      fd = fc;
      c = b - kInvPhi * (b - a);
      fc = f(c);
    } else {
      a = c;
      c = d;
      fc = fd;
      d = a + kInvPhi * (b - a);
      fd = f(d);
    }
  }
  for (const auto& [xi, fi] : {std::pair{c, fc}, std::pair{d, fd}}) {
    if (fi < *value) {
      *value = fi;
      *x = xi;
    }
  }
}

}  // namespace

PlacementSearchResult SearchBestPlacement(const PlannerClient& planner, const AverageChest& average,
                                          const ChestRegistrationResult& registration,
                                          const PlanScoreOptions& score_options,
                                          const PlacementSearchOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) ThrowUsage("placement search: " + why);
  PlacementSearchResult out;
  out.from_basis = planner.has_basis();
  std::optional<Timings::Scope> timer(std::in_place, &out.timings_s, "search");
  PlanScoreOptions fast = score_options;
  fast.map_predicted_skin = false;
  const PlanScorer scorer(planner.skin(), planner.reference_skin(), registration, average, fast);
  std::map<double, UnitResponse> responses;
  auto response = [&](double position) -> const UnitResponse& {
    auto it = responses.find(position);
    if (it != responses.end()) return it->second;
    // The response to 1 N: from the basis if the planner has one (exact to 0.001 mm, a fraction of a
    // millisecond), else a solve on the factorisation.
    std::optional<Timings::Scope> unit_timer(std::in_place, &out.timings_s, "unit_responses");
    const PlannedCase unit = planner.has_basis() ? planner.Deform({{position, false, 1.0}}, false).front()
                                                 : planner.Solve({{position, false, 1.0}}, false).front();
    unit_timer.reset();
    ++out.solves;
    UnitResponse r;
    r.skin0 = planner.skin().vertices.positions;
    r.skin_per_n = unit.skin - r.skin0;
    r.lift_per_n = unit.figures.sternum_lift_mm;
    r.linear = scorer.Linearise(r.skin0, r.skin_per_n);
    return responses.emplace(position, std::move(r)).first->second;
  };
  const bool central = options.objective != "rms";
  std::atomic<int> evaluations{0};
  // One candidate of a known response: thread-safe (the grid's rows are scored in parallel).
  auto objective = [&](const UnitResponse& r, double force) {
    evaluations.fetch_add(1, std::memory_order_relaxed);
    return scorer.Rms(r.linear, force, central);
  };
  auto evaluate = [&](double position, double force, PlanScore* keep) {
    const UnitResponse& r = response(position);
    std::optional<Timings::Scope> score_timer(std::in_place, &out.timings_s, "scoring");
    if (keep == nullptr) return objective(r, force);
    evaluations.fetch_add(1, std::memory_order_relaxed);
    *keep = scorer.Score(r.skin0 + force * r.skin_per_n);
    return central ? keep->central_roi.rms : keep->roi.rms;
  };
  // Step 1: the grid.
  for (int i = 0; i < options.positions; ++i) {
    out.positions.push_back(options.position_from +
                            (options.position_to - options.position_from) * i / (options.positions - 1));
  }
  // The force range: up to lift_limit times the largest force to lift the sternum by its depression (at
  // least 10 mm of lift, for a flat chest).
  double least_lift_per_n = std::numeric_limits<double>::infinity();
  for (double p : out.positions) least_lift_per_n = std::min(least_lift_per_n, response(p).lift_per_n);
  const double depression = std::max(10.0, planner.measurements().depression_mm);
  out.force_limit_n = options.force_max_n;
  if (least_lift_per_n > 0)
    out.force_limit_n = std::min(out.force_limit_n, options.lift_limit * depression / least_lift_per_n);
  for (int j = 1; j <= options.forces; ++j) out.forces_n.push_back(out.force_limit_n * j / options.forces);
  out.objective_mm.resize(options.positions, options.forces);
  // The best force at one position: the best of the force grid (or of its cells within `window` of
  // `near`), refined between its neighbours. `score(force)` scores a candidate at that position.
  const double kUnset = std::numeric_limits<double>::infinity();
  auto best_force_of = [&](const auto& score, const double* grid_values, double* value, int near = -1,
                           int window = 3) {
    std::vector<double> values(out.forces_n.size(), kUnset);
    for (std::size_t j = 0; j < values.size(); ++j) {
      if (grid_values != nullptr) {
        values[j] = grid_values[j];
      } else if (near < 0 || std::abs(static_cast<int>(j) - near) <= window) {
        values[j] = score(out.forces_n[j]);
      }
    }
    const auto j = static_cast<std::size_t>(std::min_element(values.begin(), values.end()) - values.begin());
    const double lo = j == 0 ? 0.0 : out.forces_n[j - 1];
    const double hi = j + 1 == values.size() ? out.force_limit_n : out.forces_n[j + 1];
    double force = out.forces_n[j];
    *value = values[j];
    GoldenSection(
        lo, hi, options.golden_iterations, [&](double f) { return f > 0 ? score(f) : 1e300; }, &force, value);
    return force;
  };
  auto best_force = [&](double position, const double* grid_values, double* value, int near = -1,
                        int window = 3) {
    return best_force_of([&](double f) { return evaluate(position, f, nullptr); }, grid_values, value, near,
                         window);
  };
  double best = std::numeric_limits<double>::infinity(), position = out.positions[0], force = out.forces_n[0];
  int bi = 0;
  auto force_index = [&](double f) {
    return static_cast<int>(std::lround(f / (out.forces_n[1] - out.forces_n[0]))) - 1;
  };
  // The grid and each row's best force, rows in parallel (their responses are all known by now).
  std::vector<double> row_value(static_cast<std::size_t>(options.positions)),
      row_force(static_cast<std::size_t>(options.positions));
  std::vector<const UnitResponse*> row_response;
  for (double p : out.positions) row_response.push_back(&response(p));
  {
    auto grid_timer = out.timings_s.Time("scoring");
#pragma omp parallel for schedule(dynamic, 1)
    for (int i = 0; i < options.positions; ++i) {
      const UnitResponse& r = *row_response[static_cast<std::size_t>(i)];
      auto score = [&](double f) { return objective(r, f); };
      for (int j = 0; j < options.forces; ++j) out.objective_mm(i, j) = score(out.forces_n[j]);
      const Eigen::VectorXd row = out.objective_mm.row(i).transpose();
      row_force[static_cast<std::size_t>(i)] =
          best_force_of(score, row.data(), &row_value[static_cast<std::size_t>(i)]);
    }
  }
  for (int i = 0; i < options.positions; ++i) {
    if (row_value[static_cast<std::size_t>(i)] < best) {
      best = row_value[static_cast<std::size_t>(i)];
      bi = i;
      position = out.positions[i];
      force = row_force[static_cast<std::size_t>(i)];
    }
  }
  // Step 2: the position between the grid's neighbours of the best, each at its best force.
  const double lo = out.positions[std::max(0, bi - 1)],
               hi = out.positions[std::min(options.positions - 1, bi + 1)];
  GoldenSection(
      lo, hi, options.golden_iterations,
      [&](double p) {
        double value = 0;
        // The best force changes little with the position: search the grid near the best one.
        const double f = best_force(p, nullptr, &value, force_index(force));
        if (value < best) {
          best = value;
          position = p;
          force = f;
        }
        return value;
      },
      &position, &best);
  out.best = {position, false, force};
  out.best_objective_mm = evaluate(position, force, &out.best_score);
  out.evaluations = evaluations.load();
  // On an edge: the refinements move the best only to a strictly lower objective, so a best still on an
  // edge of the grid means the objective falls towards that edge.
  const double position_tolerance = 1e-9 * (options.position_to - options.position_from);
  if (position <= options.position_from + position_tolerance) out.position_at_edge = -1;
  if (position >= options.position_to - position_tolerance) out.position_at_edge = 1;
  out.force_at_limit = force >= out.force_limit_n * (1 - 1e-9);
  timer.reset();
  return out;
}

}  // namespace pectus::planner
