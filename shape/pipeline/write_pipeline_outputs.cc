#include "shape/pipeline/write_pipeline_outputs.h"

#include <algorithm>

#include "shape/core/atomic_file.h"
#include "shape/core/error.h"
#include "shape/io/csv_writer.h"
#include "shape/io/landmark_io.h"
#include "shape/io/mesh_io.h"
#include "shape/model/model_figures.h"
#include "shape/model/statismo_io.h"

namespace pectus {

namespace fs = std::filesystem;

void WriteSubjectFiles(const SubjectOutcome& s, const std::function<fs::path(const fs::path&)>& target) {
  const fs::path dir = fs::path("subjects") / s.name;
  if (s.surface.num_faces() > 0) WriteMesh(target(dir / "surface.ply"), s.surface);
  if (!s.ok) return;
  WriteMesh(target(dir / "grid.ply"), s.grid.mesh);
  WriteLandmarks(target(dir / "landmarks.mrk.json"), s.landmarks);
  if (s.to_mean.distances.size() > 0) {
    TriangleMesh coloured = s.grid.mesh;
    coloured.vertices.scalars["distance_mm"] = s.to_mean.distances;
    const double r = std::max(1.0, s.to_mean.stats.max_abs);
    coloured.vertices.colors = ColorsForValues(s.to_mean.distances, -r, r);
    WriteMesh(target(dir / "distance_to_mean.ply"), coloured);
  }
}

namespace {

// The model's own files, largest first: model.h5, scores.csv, mean.ply, eigen.csv.
std::vector<OutputFile> ModelOwnFiles(const ShapeModel& m, const nlohmann::json& model_info) {
  std::vector<OutputFile> files;
  files.push_back(
      {"model.h5", [&m, model_info](const fs::path& to) { WriteStatismoModel(to, m, model_info); }});
  files.push_back({"scores.csv", [&m](const fs::path& to) {
                     std::vector<std::string> header{"subject"};
                     for (int k = 1; k <= m.num_modes(); ++k)
                       header.push_back("mode" + std::to_string(k) + "_mm");
                     WriteCsv(to, header, m.scores, m.names);  // N by k, a row per subject
                   }});
  files.push_back({"mean.ply", [&m](const fs::path& to) { WriteMesh(to, m.ToMesh(m.mean)); }});
  files.push_back({"eigen.csv", [&m](const fs::path& to) {
                     Eigen::MatrixXd eigen(m.num_modes(), 4);
                     eigen.col(0) = Eigen::VectorXd::LinSpaced(m.num_modes(), 1, m.num_modes());
                     eigen.col(1) = m.variances;
                     eigen.col(2) = m.ExplainedFraction();
                     eigen.col(3) = m.CumulativeFraction();
                     WriteCsv(to, {"mode", "eigenvalue_mm2", "explained", "cumulative"}, eigen);
                   }});
  return files;
}

}  // namespace

std::vector<OutputFile> ModelOutputFiles(const ShapeModel& model, const nlohmann::json& model_info,
                                         const PipelineReportOptions& report) {
  std::vector<OutputFile> files = ModelOwnFiles(model, model_info);
  for (ReportFigure& figure : ModelReportFigures(model, static_cast<int>(model.scores.rows()), report)) {
    files.push_back({figure.path, [make = std::move(figure.make)](const fs::path& to) {
                       WriteFileAtomically(to, make());
                     }});
  }
  return files;
}

std::vector<fs::path> WriteModelFiles(const ShapeModel* model, const ModelQualityCurves* quality,
                                      const nlohmann::json& model_info, const fs::path& folder,
                                      const std::function<fs::path(const fs::path&)>& stage) {
  std::vector<fs::path> written;
  auto target = [&](const fs::path& name) {
    written.push_back(folder / name);
    return stage(folder / name);
  };
  if (model) {
    for (const OutputFile& file : ModelOwnFiles(*model, model_info)) file.write(target(file.path));
  }
  if (quality) {
    const ModelQualityCurves& q = *quality;
    Eigen::MatrixXd table(q.modes.size(), 7);
    table << q.modes.cast<double>(), q.compactness, q.compactness_sd, q.generalization_mm,
        q.generalization_sd, q.specificity_mm, q.specificity_sd;
    WriteCsv(target("quality.csv"),
             {"modes", "compactness_mm2", "compactness_sd_mm2", "generalization_mm", "generalization_sd_mm",
              "specificity_mm", "specificity_sd_mm"},
             table);
  }
  return written;
}

namespace {

// The entries of `from` one level down (subjects/NAME, figures/distance_NAME.png), in name order.
std::vector<fs::path> EntriesOneLevelDown(const fs::path& from) {
  std::vector<fs::path> entries;
  std::error_code ec;
  for (const fs::directory_entry& top : fs::directory_iterator(from, ec)) {
    if (!top.is_directory()) {
      entries.push_back(top.path().filename());
      continue;
    }
    for (const fs::directory_entry& e : fs::directory_iterator(top.path(), ec))
      entries.push_back(top.path().filename() / e.path().filename());
  }
  std::sort(entries.begin(), entries.end());
  return entries;
}

}  // namespace

std::vector<fs::path> WritePipelineOutputs(
    const PipelineResult& result, const PipelineReportOptions& report, const nlohmann::json& model_info,
    const fs::path& folder, const std::function<fs::path(const fs::path&)>& stage, const fs::path& work,
    bool model_files_written, const std::function<void(const fs::path&, const fs::path&)>& move) {
  std::vector<fs::path> written;
  auto target = [&](const fs::path& name) {
    written.push_back(folder / name);
    return stage(folder / name);
  };
  // The model and its tables.
  if (!model_files_written) {
    written = WriteModelFiles(result.model ? &*result.model : nullptr,
                              result.quality ? &*result.quality : nullptr, model_info, folder, stage);
  }
  // Each subject's meshes and landmarks (and its picture in the report): made on the farm, or here.
  for (const SubjectOutcome& s : result.subjects) {
    if (work.empty()) {
      WriteSubjectFiles(s, [&](const fs::path& name) { return target(name); });
    } else if (move) {  // its folder and picture whole, at the commit
      const fs::path from = SubjectFilesFolder(work, s.name);
      for (const fs::path& name : EntriesOneLevelDown(from)) {
        written.push_back(folder / name);
        move(from / name, folder / name);
      }
    } else {
      MoveFilesInto(SubjectFilesFolder(work, s.name), target);
    }
  }
  // The files of the model alone, made on the farm (PipelineRun::model_files).
  const bool model_files_made = !work.empty() && move && fs::is_directory(ModelFilesFolder(work));
  if (model_files_made) {
    for (const fs::path& name : EntriesOneLevelDown(ModelFilesFolder(work))) {
      written.push_back(folder / name);
      move(ModelFilesFolder(work) / name, folder / name);
    }
  }
  // The report and its figures.
  PipelineReportOptions report_options = report;
  report_options.subject_pictures_made = !work.empty();
  report_options.model_figures_made = model_files_made;
  for (const ReportFile& file : MakePipelineReport(result, report_options)) {
    WriteFileAtomically(target(file.path), file.bytes);
  }
  return written;
}

}  // namespace pectus
