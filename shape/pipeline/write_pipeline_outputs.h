// pectus: every file of a pipeline run, written in one place (as WriteNussPlan does for the planner): the
// model, its tables, each subject's meshes and landmarks, and the HTML report with its figures.
#pragma once

#include <filesystem>
#include <functional>
#include <nlohmann/json.hpp>
#include <vector>

#include "shape/pipeline/cohort_pipeline.h"
#include "shape/pipeline/pipeline_report.h"

namespace pectus {

/// Writes the pipeline's files into `folder`. With a model: model.h5 (statismo; `model_info` goes into its
/// /pectus info), mean.ply, scores.csv (one row per subject of the model: its name, then its score on
/// each mode, mm), eigen.csv (mode, eigenvalue_mm2, explained, cumulative); with quality curves:
/// quality.csv. Per subject under subjects/NAME/: surface.ply (the registered surface, if kept and made),
/// and for a subject that made it grid.ply, landmarks.mrk.json and distance_to_mean.ply (coloured, scalar
/// distance_mm). Then report.html and its figures (MakePipelineReport). Each file goes through
/// `stage(target)`, which returns the path to write it to (a transaction's staging). Returns the target
/// paths written. Throws Error(kFailure) naming a file that cannot be written.
/// With `work` (PipelineRun::work of a run whose subject_files were WriteSubjectFiles and subject_pictures
/// SubjectDistancePicture), each subject's files were made on the farm: they are moved from
/// SubjectFilesFolder(work, NAME) rather than written from `result` (whose subjects have no surface then).
/// `model_files_written`: the caller writes the model's files itself (WriteModelFiles, e.g. in a thread
/// beside this one: `stage` must then be safe to call from both).
std::vector<std::filesystem::path> WritePipelineOutputs(
    const PipelineResult& result, const PipelineReportOptions& report, const nlohmann::json& model_info,
    const std::filesystem::path& folder,
    const std::function<std::filesystem::path(const std::filesystem::path&)>& stage,
    const std::filesystem::path& work = {}, bool model_files_written = false);

/// The files of WritePipelineOutputs that need only the model and its quality curves (either may be null):
/// model.h5, mean.ply, scores.csv, eigen.csv, quality.csv, each through `stage` as there. Returns the target
/// paths written.
std::vector<std::filesystem::path> WriteModelFiles(
    const ShapeModel* model, const ModelQualityCurves* quality, const nlohmann::json& model_info,
    const std::filesystem::path& folder,
    const std::function<std::filesystem::path(const std::filesystem::path&)>& stage);

/// One subject's files: under subjects/NAME/, surface.ply (its registered surface, if kept and made) and,
/// if it made it, grid.ply, landmarks.mrk.json and distance_to_mean.ply (coloured, scalar distance_mm).
/// Each goes to `target(relative path)`.
void WriteSubjectFiles(const SubjectOutcome& subject,
                       const std::function<std::filesystem::path(const std::filesystem::path&)>& target);

}  // namespace pectus
