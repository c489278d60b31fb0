// pectus: the pipeline's HTML report: one page with the pictures (mean shape, modes, variance explained,
// model quality, each subject's distance to the mean on one colour scale) and the numbers (per subject and
// per stage), made as a set of files for the caller to write.
#pragma once

#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "shape/pipeline/cohort_pipeline.h"

namespace pectus {

/// What the report shows.
struct PipelineReportOptions {
  std::string title = "pectus: the average chest";
  /// Colour scale of the distance maps, +-mm (0: the largest 99th percentile of |d| over the subjects,
  /// rounded up to a whole mm), so that every subject is shown on the same scale.
  double distance_range_mm = 0.0;
  int modes = 3;         ///< modes pictured (at +-mode_sd standard deviations)
  double mode_sd = 2.0;  ///< > 0
  int picture_px = 420;  ///< height of the surface pictures
  nlohmann::json run;    ///< shown as "run" facts: the command, the folders, wall time (any JSON object)
  /// The subjects' distance pictures are made elsewhere (SubjectDistancePicture, one task per subject on
  /// the farm): MakePipelineReport only shows them.
  bool subject_pictures_made = false;
  /// The figures of the model alone (ModelReportFigures, tasks of the farm) are made elsewhere too.
  bool model_figures_made = false;
};

/// One file of the report, relative to the output folder ("report.html", "figures/mean.png").
struct ReportFile {
  std::string path;
  std::string bytes;
};

/// The report's files: report.html and the PNGs it shows under figures/. Never throws for a cohort in
/// which subjects failed: they are listed with their stage and message.
std::vector<ReportFile> MakePipelineReport(const PipelineResult& result,
                                           const PipelineReportOptions& options = {});

/// One figure of the report that needs only the model, made when asked (on whichever process).
struct ReportFigure {
  std::string path;                   ///< relative to the output folder ("figures/mode_1.png")
  std::function<std::string()> make;  ///< its PNG bytes
};

/// The report's figures of the model alone, as MakePipelineReport shows them: figures/mean_sd.png (the
/// mean of `subjects` subjects coloured by the model's SD per vertex), figures/variance.png, and
/// figures/mode_K.png for the first options.modes modes. `model` must outlive the figures.
std::vector<ReportFigure> ModelReportFigures(const ShapeModel& model, int subjects,
                                             const PipelineReportOptions& options);

/// The colour scale of the distance maps, +-mm: options.distance_range_mm, or if that is 0, the largest
/// 99th percentile of |d| over the subjects rounded up to a whole mm (at least 1).
double DistanceMapRange(const std::vector<SubjectOutcome>& subjects, const PipelineReportOptions& options);

/// The report's path of a subject's distance picture: "figures/distance_NAME.png".
std::string SubjectPicturePath(const SubjectOutcome& subject);

/// A subject's distance to the mean pictured on its grid, on the scale +-range_mm (DistanceMapRange), as the
/// report shows it (a subject with distances to the mean).
ReportFile SubjectDistancePicture(const SubjectOutcome& subject, double range_mm,
                                  const PipelineReportOptions& options);

/// The per-subject and per-model figures as JSON (for --report): one object per subject with its stage
/// results, and the model's variance table.
nlohmann::json PipelineJson(const PipelineResult& result);

}  // namespace pectus
