#include "shape/pipeline/pipeline_report.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "shape/model/model_figures.h"
#include "shape/model/shape_grid.h"
#include "shape/render/mesh_render.h"

namespace pectus {
namespace {

std::string Escape(const std::string& text) {
  std::string out;
  for (char c : text) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      default: out += c;
    }
  }
  return out;
}

std::string Num(double x, int decimals = 2) {
  if (!std::isfinite(x)) return "&ndash;";
  char text[64];
  std::snprintf(text, sizeof(text), "%.*f", decimals, x);
  return text;
}

// Per-vertex standard deviation of the model (mm): sqrt(sum_c lambda_c |e_c at the vertex|^2).
Eigen::VectorXd VertexSd(const ShapeModel& model) {
  Eigen::VectorXd var = Eigen::VectorXd::Zero(model.num_points());
  for (int c = 0; c < model.num_modes(); ++c) {
    const Eigen::Map<const Points3> e(model.basis.col(c).data(), model.num_points(), 3);
    var += model.variances[c] * e.rowwise().squaredNorm();
  }
  return var.cwiseSqrt();
}

nlohmann::json MatrixJson(const Eigen::Matrix4d& M) {
  nlohmann::json rows = nlohmann::json::array();
  for (int r = 0; r < 4; ++r) rows.push_back({M(r, 0), M(r, 1), M(r, 2), M(r, 3)});
  return rows;
}

}  // namespace

nlohmann::json PipelineJson(const PipelineResult& r) {
  nlohmann::json subjects = nlohmann::json::array();
  for (const SubjectOutcome& s : r.subjects) {
    nlohmann::json j = {{"name", s.name},
                        {"ok", s.ok},
                        {"sweeps", s.sweeps},
                        {"points_in", s.points_in},
                        {"points_merged", s.points_merged},
                        {"merge_rms_mm", s.merge_rms_mm},
                        {"faces", s.faces},
                        {"rbf_fitting_accuracy_mm", s.fit_accuracy_mm},
                        {"T_reference_subject", MatrixJson(s.T_reference_subject.Matrix())},
                        {"scale", s.T_reference_subject.scale},
                        {"landmark_rms_mm", s.landmark_rms_mm},
                        {"icp_rms_mm", s.icp_rms_mm},
                        {"icp_accepted", s.icp_accepted},
                        {"registration", s.registration_message}};
    nlohmann::json files = nlohmann::json::array();
    for (const auto& f : s.sweep_files) files.push_back(f.filename().string());
    j["sweep_files"] = files;
    nlohmann::json poses = nlohmann::json::array();  // the merge's pose of each file, as T_reference_subject
    for (const Rigid3& T : s.T_subject_sweep) poses.push_back(MatrixJson(T.matrix()));
    j["T_subject_sweep"] = poses;
    if (!s.ok) j["failed_stage"] = s.failed_stage, j["error"] = s.error;
    if (s.ok) {  // resampled (a summary has no grid)
      j["resample"] = {{"fit_rms_mm", s.grid.fit_rms_mm},
                       {"max_data_gap_mm", s.grid.max_data_gap_mm},
                       {"supported_fraction", s.grid.supported_fraction},
                       {"vertices_filled_from_cohort", s.vertices_filled_from_cohort},
                       {"largest_fill_change_mm", s.largest_fill_change_mm}};
      j["measures"] = s.measures.ToJson();
    }
    if (s.to_mean.stats.count > 0) j["distance_to_mean"] = s.to_mean.stats.ToJson();
    j["timings_s"] = s.timings_s.ToJson();
    subjects.push_back(j);
  }
  nlohmann::json out = {
      {"subjects", subjects}, {"reference", r.reference}, {"succeeded", r.succeeded}, {"message", r.message}};
  if (!r.imputation_message.empty()) out["imputation"] = r.imputation_message;
  if (r.model) {
    nlohmann::json modes = nlohmann::json::array();
    const Eigen::VectorXd f = r.model->ExplainedFraction(), c = r.model->CumulativeFraction();
    for (int k = 0; k < r.model->num_modes(); ++k) {
      modes.push_back({{"mode", k + 1},
                       {"eigenvalue_mm2", r.model->variances[k]},
                       {"explained", f[k]},
                       {"cumulative", c[k]}});
    }
    out["model"] = {{"points", r.model->num_points()},
                    {"modes", modes},
                    {"total_variance_mm2", r.model->total_variance},
                    {"mean_measures", r.mean_measures.ToJson()}};
  }
  if (r.quality) {
    nlohmann::json q = nlohmann::json::array();
    for (Eigen::Index m = 0; m < r.quality->modes.size(); ++m) {
      q.push_back({{"modes", r.quality->modes[m]},
                   {"compactness_mm2", r.quality->compactness[m]},
                   {"generalization_mm", r.quality->generalization_mm[m]},
                   {"specificity_mm", r.quality->specificity_mm[m]}});
    }
    out["quality"] = q;
  }
  return out;
}

double DistanceMapRange(const std::vector<SubjectOutcome>& subjects, const PipelineReportOptions& o) {
  if (o.distance_range_mm > 0.0) return o.distance_range_mm;
  double range = 0.0;
  for (const SubjectOutcome& s : subjects) {
    if (s.to_mean.stats.count > 0) range = std::max(range, s.to_mean.stats.p99);
  }
  return std::max(1.0, std::ceil(range));
}

std::string SubjectPicturePath(const SubjectOutcome& s) { return "figures/distance_" + s.name + ".png"; }

ReportFile SubjectDistancePicture(const SubjectOutcome& s, double range_mm, const PipelineReportOptions& o) {
  SurfaceMapFigure fig;
  fig.title = s.name;
  fig.min = -range_mm;
  fig.max = range_mm;
  fig.up = -s.grid.roi.sternal;
  fig.size = o.picture_px;
  return {SubjectPicturePath(s),
          render::EncodePng(SurfaceMapImage(s.grid.mesh, s.to_mean.distances, s.grid.roi.normal, fig))};
}

std::vector<ReportFigure> ModelReportFigures(const ShapeModel& m, int subjects,
                                             const PipelineReportOptions& o) {
  std::vector<ReportFigure> figures;
  figures.push_back({"figures/mean_sd.png", [&m, subjects, o] {
                       const Eigen::VectorXd sd = VertexSd(m);
                       SurfaceMapFigure figure;
                       figure.title = "mean of " + std::to_string(subjects) + ": model SD per vertex";
                       figure.label = "SD, mm";
                       figure.min = 0.0;
                       figure.max = std::max(1e-3, sd.maxCoeff());
                       figure.size = o.picture_px;
                       return render::EncodePng(
                           SurfaceMapImage(m.ToMesh(m.mean), sd, Eigen::Vector3d::Zero(), figure));
                     }});
  figures.push_back({"figures/variance.png", [&m] { return render::EncodePng(VarianceExplainedImage(m)); }});
  for (int k = 1; k <= std::min(o.modes, m.num_modes()); ++k) {
    figures.push_back({"figures/mode_" + std::to_string(k) + ".png", [&m, k, sd = o.mode_sd] {
                         return render::EncodePng(ModeDisplacementImage(m, k, sd));
                       }});
  }
  return figures;
}

std::vector<ReportFile> MakePipelineReport(const PipelineResult& r, const PipelineReportOptions& o) {
  std::vector<ReportFile> files;
  auto figure = [&](const std::string& name, const render::Image& image) {
    files.push_back({"figures/" + name, render::EncodePng(image)});
    return "figures/" + name;
  };
  std::ostringstream html;
  html << "<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>" << Escape(o.title) << "</title>\n"
       << "<style>body{font-family:sans-serif;margin:2em;max-width:1400px}table{border-collapse:collapse;"
          "margin:1em 0}td,th{border:1px solid #ccc;padding:3px 8px;text-align:right}th{background:#eee}"
          "td.l{text-align:left}.bad{background:#fdd}img{max-width:100%;margin:4px}"
          ".maps{display:flex;flex-wrap:wrap}.maps "
          "div{text-align:center;font-size:small}</style></head><body>\n"
       << "<h1>" << Escape(o.title) << "</h1>\n<p>" << Escape(r.message) << ".</p>\n";

  // The run.
  html << "<h2>Run</h2>\n<table>";
  for (const auto& [key, value] : o.run.items()) {
    html << "<tr><th>" << Escape(key) << "</th><td class=\"l\">"
         << Escape(value.is_string() ? value.get<std::string>() : value.dump()) << "</td></tr>";
  }
  for (const auto& [stage, t] : r.timings_s.stages())
    html << "<tr><th>" << Escape(stage) << " (s, summed)</th><td>" << Num(t) << "</td></tr>";
  html << "</table>\n";

  // Per subject.
  html << "<h2>Subjects</h2>\n<table><tr><th>subject</th><th>status</th><th>sweeps</th><th>points</th>"
          "<th>merge RMS mm</th><th>triangles</th><th>landmark RMS mm</th><th>ICP RMS mm</th><th>profile fit "
          "RMS mm</th>"
          "<th>largest data gap mm</th><th>depression mm</th><th>to mean RMS mm</th><th>to mean max mm</th>"
          "<th>time s</th></tr>\n";
  for (const SubjectOutcome& s : r.subjects) {
    const double total = s.timings_s.Total();
    html << "<tr" << (s.ok ? "" : " class=\"bad\"") << "><td class=\"l\">" << Escape(s.name)
         << (s.name == r.reference ? " (reference)" : "") << "</td><td class=\"l\">"
         << (s.ok ? "ok" : "failed at " + Escape(s.failed_stage)) << "</td><td>" << s.sweeps << "</td><td>"
         << s.points_merged << "</td><td>" << Num(s.merge_rms_mm) << "</td><td>" << s.faces << "</td><td>"
         << Num(s.landmark_rms_mm) << "</td><td>" << Num(s.icp_rms_mm)
         << (s.ok && !s.icp_accepted ? " (not kept)" : "") << "</td><td>"
         << (s.ok ? Num(s.grid.fit_rms_mm, 3) : "") << "</td><td>"
         << (s.ok ? Num(s.grid.max_data_gap_mm, 1) : "") << "</td><td>"
         << (s.ok ? Num(s.measures.depression_depth_mm, 1) : "") << "</td><td>"
         << (s.to_mean.stats.count > 0 ? Num(s.to_mean.stats.rms) : "") << "</td><td>"
         << (s.to_mean.stats.count > 0 ? Num(s.to_mean.stats.max_abs) : "") << "</td><td>" << Num(total, 1)
         << "</td></tr>\n";
  }
  html << "</table>\n";
  for (const SubjectOutcome& s : r.subjects) {
    if (!s.ok)
      html << "<p class=\"bad\"><b>" << Escape(s.name) << "</b> failed at " << Escape(s.failed_stage) << ": "
           << Escape(s.error) << "</p>\n";
  }
  if (!r.model) {
    html << "<p class=\"bad\">Fewer than two subjects made it: no model.</p></body></html>\n";
    files.push_back({"report.html", html.str()});
    return files;
  }

  // The average chest and its variability.
  const ShapeModel& m = *r.model;
  if (!o.model_figures_made) {
    for (const ReportFigure& f : ModelReportFigures(m, r.succeeded, o)) files.push_back({f.path, f.make()});
  }
  html << "<h2>The average chest</h2>\n<p>Mean of " << r.succeeded << " resampled subjects ("
       << m.num_points() << " grid vertices); depression of the mean "
       << Num(r.mean_measures.depression_depth_mm, 1) << " mm. Total variance " << Num(m.total_variance, 1)
       << " mm&sup2;.</p>\n<img src=\"figures/mean_sd.png\">\n<img src=\"figures/variance.png\">\n";
  html << "<table><tr><th>mode</th><th>eigenvalue mm&sup2;</th><th>SD mm</th><th>explained "
          "%</th><th>cumulative %</th></tr>";
  const Eigen::VectorXd f = m.ExplainedFraction(), c = m.CumulativeFraction();
  for (int k = 0; k < std::min(10, m.num_modes()); ++k) {
    html << "<tr><td>" << k + 1 << "</td><td>" << Num(m.variances[k]) << "</td><td>"
         << Num(std::sqrt(m.variances[k])) << "</td><td>" << Num(100 * f[k], 1) << "</td><td>"
         << Num(100 * c[k], 1) << "</td></tr>";
  }
  html << "</table>\n<h2>Principal modes</h2>\n<div class=\"maps\">";
  for (int k = 1; k <= std::min(o.modes, m.num_modes()); ++k)
    html << "<img src=\"figures/mode_" << k << ".png\">";
  html << "</div>\n";

  // Model quality.
  if (r.quality) {
    const ModelQualityCurves& q = *r.quality;
    html << "<h2>Model quality (Styner et al. 2003)</h2>\n<img src=\""
         << figure("quality.png", QualityCurvesImage(q))
         << "\">\n<table><tr><th>modes M</th><th>compactness mm&sup2;</th><th>generalization mm</th>"
            "<th>specificity mm</th></tr>";
    for (Eigen::Index k = 0; k < q.modes.size(); ++k) {
      html << "<tr><td>" << q.modes[k] << "</td><td>" << Num(q.compactness[k]) << "</td><td>"
           << Num(q.generalization_mm[k], 3) << " &plusmn; " << Num(q.generalization_sd[k], 3) << "</td><td>"
           << Num(q.specificity_mm[k], 3) << " &plusmn; " << Num(q.specificity_sd[k], 3) << "</td></tr>";
    }
    html << "</table>\n";
  }

  // Distance maps on one scale.
  const double range = DistanceMapRange(r.subjects, o);
  html << "<h2>Each subject against the mean</h2>\n<p>Signed distance of each resampled subject to the mean "
          "shape "
          "(positive: in front of the mean), one colour scale &plusmn;"
       << Num(range, 1) << " mm.</p>\n<div class=\"maps\">";
  for (const SubjectOutcome& s : r.subjects) {
    if (s.to_mean.stats.count == 0) continue;
    std::string picture = SubjectPicturePath(s);
    if (!o.subject_pictures_made) {
      ReportFile file = SubjectDistancePicture(s, range, o);
      picture = file.path;
      files.push_back(std::move(file));
    }
    html << "<div><img src=\"" << picture << "\"><br>RMS " << Num(s.to_mean.stats.rms) << " mm, max "
         << Num(s.to_mean.stats.max_abs) << " mm</div>";
  }
  html << "</div>\n<p>Stage times per subject are in the JSON report; merge "
       << Num(r.timings_s.Seconds("merge"), 1) << " s, reconstruct "
       << Num(r.timings_s.Seconds("reconstruct"), 1) << " s, register "
       << Num(r.timings_s.Seconds("register"), 1) << " s, resample "
       << Num(r.timings_s.Seconds("resample"), 1) << " s (summed over subjects).</p>\n</body></html>\n";
  files.push_back({"report.html", html.str()});
  return files;
}

}  // namespace pectus
