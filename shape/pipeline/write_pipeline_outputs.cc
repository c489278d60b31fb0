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

std::vector<fs::path> WriteModelFiles(const ShapeModel* model, const ModelQualityCurves* quality,
                                      const nlohmann::json& model_info, const fs::path& folder,
                                      const std::function<fs::path(const fs::path&)>& stage) {
  std::vector<fs::path> written;
  auto target = [&](const fs::path& name) {
    written.push_back(folder / name);
    return stage(folder / name);
  };
  if (model) {
    const ShapeModel& m = *model;
    WriteStatismoModel(target("model.h5"), m, model_info);
    WriteMesh(target("mean.ply"), m.ToMesh(m.mean));
    std::vector<std::string> header{"subject"};
    for (int k = 1; k <= m.num_modes(); ++k) header.push_back("mode" + std::to_string(k) + "_mm");
    WriteCsv(target("scores.csv"), header, m.scores, m.names);  // N by k, a row per subject
    Eigen::MatrixXd eigen(m.num_modes(), 4);
    eigen.col(0) = Eigen::VectorXd::LinSpaced(m.num_modes(), 1, m.num_modes());
    eigen.col(1) = m.variances;
    eigen.col(2) = m.ExplainedFraction();
    eigen.col(3) = m.CumulativeFraction();
    WriteCsv(target("eigen.csv"), {"mode", "eigenvalue_mm2", "explained", "cumulative"}, eigen);
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

std::vector<fs::path> WritePipelineOutputs(const PipelineResult& result, const PipelineReportOptions& report,
                                           const nlohmann::json& model_info, const fs::path& folder,
                                           const std::function<fs::path(const fs::path&)>& stage,
                                           const fs::path& work, bool model_files_written) {
  std::vector<fs::path> written;
  auto target = [&](const fs::path& name) {
    written.push_back(folder / name);
    return stage(folder / name);
  };
  // The model and its tables.
  if (!model_files_written) {
    written = WriteModelFiles(result.model ? &*result.model : nullptr, result.quality ? &*result.quality : nullptr,
                              model_info, folder, stage);
  }
  // Each subject's meshes and landmarks (and its picture in the report): made on the farm, or here.
  for (const SubjectOutcome& s : result.subjects) {
    if (work.empty()) {
      WriteSubjectFiles(s, [&](const fs::path& name) { return target(name); });
    } else {
      MoveFilesInto(SubjectFilesFolder(work, s.name), target);
    }
  }
  // The report and its figures.
  PipelineReportOptions report_options = report;
  report_options.subject_pictures_made = !work.empty();
  for (const ReportFile& file : MakePipelineReport(result, report_options)) {
    WriteFileAtomically(target(file.path), file.bytes);
  }
  return written;
}

}  // namespace pectus
