#include "planner_plugin/host/internal/plan_report.h"

#include <cstdio>
#include <sstream>

namespace pectus::planner {
namespace {

std::string Escape(const std::string& text) {
  std::string out;
  for (char c : text) {
    switch (c) {
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '&': out += "&amp;"; break;
      case '"': out += "&quot;"; break;
      default: out += c;
    }
  }
  return out;
}

std::string Num(double value, const char* format = "%.1f") {
  char text[64];
  std::snprintf(text, sizeof(text), format, value);
  return text;
}

std::string Row(const std::vector<std::string>& cells, bool header = false) {
  std::string out = "<tr>";
  for (const std::string& c : cells) out += (header ? "<th>" : "<td>") + c + (header ? "</th>" : "</td>");
  return out + "</tr>\n";
}

std::string Picture(const std::string& file, const std::string& caption) {
  if (file.empty()) return "";
  return "<figure><img src=\"" + Escape(file) + "\" alt=\"" + Escape(caption) + "\"><figcaption>" +
         Escape(caption) + "</figcaption></figure>\n";
}

}  // namespace

std::string PlanReportHtml(const PlanReportInput& in) {
  const PectusPlannerPatient& p = in.patient;
  const PectusPlannerMeasurements& m = in.measured;
  const double magnification = p.magnification > 0 ? p.magnification : 1.0;
  std::ostringstream h;
  h << "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>pectus plan: patient "
    << Escape(p.id) << "</title>\n<style>body{font-family:sans-serif;max-width:1200px;margin:2em auto;}"
    << "table{border-collapse:collapse;margin:1em 0}td,th{border:1px solid #bbb;padding:4px "
       "10px;text-align:right}"
    << "th{background:#eee}figure{display:inline-block;margin:0.5em}img{max-width:100%}"
    << "p.note{color:#555}.warn{color:#b00}</style></head><body>\n";
  h << "<h1>Nuss procedure plan: patient " << Escape(p.id) << "</h1>\n";
  h << "<p class=\"note\">Planner: " << Escape(in.plugin) << ". Average chest: " << Escape(in.average_chest)
    << ". Lengths in mm, forces in N.</p>\n";

  h << "<h2>Patient-specific ribcage</h2>\n<p>The generic ribcage scaled and deformed to the CT measurements "
    << "(dissertation §4.1.1); measuring the generated ribcage the way the CT was measured gives "
       "back:</p>\n<table>"
    << Row({"", "width", "depth", "sternal length", "depression", "Haller index"}, true)
    << Row({"CT", Num(p.width_mm / magnification), Num(p.depth_mm / magnification),
            Num(p.slice_spacing_mm > 0 ? (p.last_sternum_slice - p.first_sternum_slice) * p.slice_spacing_mm
                                       : p.sternal_length_mm),
            Num(p.depression_mm / magnification),
            p.ct_haller_index > 0 ? Num(p.ct_haller_index, "%.2f") : "-"})
    << Row({"model", Num(m.width_mm), Num(m.depth_mm), Num(m.sternal_length_mm), Num(m.depression_mm),
            Num(m.haller_index, "%.2f")})
    << "</table>\n<p>Fit: " << (m.fit_converged ? "converged" : "best iterate") << " after "
    << m.fit_iterations << " iterations, largest residual " << Num(m.fit_residual_mm, "%.3f")
    << " mm. Mesh: " << m.nodes << " nodes, " << m.tets << " quadratic tetrahedra, " << m.free_dofs
    << " unknowns, assembled and factorised once in " << Num(m.factorization_seconds, "%.1f")
    << " s. Materials (E MPa / &nu;): sternum " << Num(in.options.sternum_youngs_modulus_mpa, "%g") << "/"
    << Num(in.options.sternum_poisson_ratio, "%g") << ", ribs "
    << Num(in.options.rib_youngs_modulus_mpa, "%g") << "/" << Num(in.options.rib_poisson_ratio, "%g")
    << ", costal cartilage " << Num(in.options.cartilage_youngs_modulus_mpa, "%g") << "/"
    << Num(in.options.cartilage_poisson_ratio, "%g") << ".</p>\n";

  h << "<h2>Force to lift the sternum by its depression</h2>\n<table>"
    << Row({"bar position", "lift per 100 N, mm", "force to lift " + Num(m.depression_mm) + " mm, N"}, true);
  for (std::size_t i = 0; i < in.force_to_lift.size() && i < in.lift_positions.size(); ++i) {
    h << Row({Escape(in.lift_positions[i].Name().substr(0, in.lift_positions[i].Name().find(','))),
              Num(100 * in.force_to_lift[i].lift_per_newton_mm, "%.2f"),
              Num(in.force_to_lift[i].force_n, "%.0f")});
  }
  h << "</table>\n<p class=\"note\">In vivo, about 175 N for adolescents and above 200 N for adults (Weber "
       "et al., "
    << "J Thorac Cardiovasc Surg 2006); the dissertation's model about 1000 N for 20 mm. docs/planner.md "
       "discusses "
    << "the difference.</p>\n";

  h << "<h2>Scenarios against the average chest</h2>\n<p>The patient's chest is registered to the average "
       "chest "
    << "once, by its landmarks (sternal notch, manubrium, xiphoid) as they would lie without the deformity, "
       "and "
    << "every predicted chest is compared with the average chest over the region of interest, in depth along "
    << "the average chest's anterior direction; positive: the predicted chest lies in front. "
    << (in.relative
            ? "Skin model: relative (the average chest carrying the patient's deformity and the bar's "
              "correction, dissertation §5.3). "
            : "Skin model: the modelled skin (the ribcage plus a uniform soft-tissue layer). ")
    << "Scenarios A and B share one colour scale, &plusmn;" << Num(in.common_limit_mm)
    << " mm (the worse of the two, as in the dissertation's Fig. 77); the unoperated chest and the best "
       "placement "
    << "share &plusmn;" << Num(in.outcome_limit_mm) << " mm.</p>\n<table>"
    << Row({"scenario", "bar", "sternal lift", "lift / depression", "RMS", "max |d|", "mean", "central RMS",
            "central max |d|"},
           true)
    << Row({"before", "none", "0", "0", Num(in.before.rms), Num(in.before.max_abs), Num(in.before.mean), "",
            ""});
  std::string beyond;
  for (const ReportScenario& s : in.scenarios) {
    const double lift = s.figures.sternum_lift_mm, depression = s.sternum_lift_needed_mm;
    std::string ratio = depression > 0 ? Num(lift / depression) : "-";
    if (lift > LinearRangeLiftMm(depression)) {
      ratio = "<b class=\"warn\">" + ratio + ": beyond the model</b>";
      beyond += (beyond.empty() ? "" : ", ") + Escape(s.name);
    }
    h << Row({Escape(s.name), Escape(s.bar.Name()), Num(lift), ratio, Num(s.roi.rms), Num(s.roi.max_abs),
              Num(s.roi.mean), Num(s.central.rms), Num(s.central.max_abs)});
  }
  h << "</table>\n";
  if (!beyond.empty()) {
    h << "<p class=\"warn\">Scenario " << beyond << " lifts the sternum by more than "
      << Num(LinearRangeLiftMm(in.scenarios.front().sternum_lift_needed_mm), "%.0f")
      << " mm (twice the depression, at least 20 mm): the linear model is far outside its range there, so "
         "its chest is not a prediction. Use a force near the force to lift above.</p>\n";
  }
  h << Picture(in.comparison_png, "predicted chest minus average chest, scenarios side by side")
    << (in.search == nullptr ? Picture(in.before_png, "before the operation") : "")
    << Picture(in.ribcage_png, in.search != nullptr ? "the deformed ribcage, best placement"
                                                    : "the deformed ribcage, scenario A");

  if (in.search != nullptr) {
    const PlacementSearchResult& s = *in.search;
    h << "<h2>Best bar placement</h2>\n<p>The placement minimising the RMS difference to the average chest "
         "over "
      << s.positions.size() << " positions x " << s.forces_n.size() << " forces, refined: <b>"
      << Escape(s.best.Name()) << "</b>, RMS " << Num(s.best_objective_mm) << " mm, max |d| "
      << Num(s.best_score.roi.max_abs) << " mm (" << s.evaluations << " chests scored, " << s.solves
      << " solves on the one factorisation, " << Num(s.timings_s.Total(), "%.1f") << " s).</p>\n"
      << (s.position_at_edge != 0 || s.force_at_limit
              ? "<p class=\"warn\">" + Escape(SearchEdgeNote(s)) + "</p>\n"
              : std::string())
      << Picture(in.search_png, "RMS difference over bar position and force; the cross marks the best")
      << Picture(in.best_png, "before the operation and with the best placement, on one scale");
  }
  h << "</body></html>\n";
  return h.str();
}

}  // namespace pectus::planner
