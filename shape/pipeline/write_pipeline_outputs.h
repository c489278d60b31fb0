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
/// With `move` as well, those files are not moved now: each entry one level down in a subject's folder
/// (its subjects/NAME/ folder, its figures/ picture) goes whole to `move(from, target)` (a transaction's
/// MoveAtCommit: the work folder keeps them until the outputs are committed, for --resume); and if the
/// files of the model were made on the farm (PipelineRun::model_files, in ModelFilesFolder(work)), they go
/// to `move` too and the report does not make its figures of the model again.
/// `model_files_written`: the caller writes the model's files itself (WriteModelFiles, e.g. in a thread
/// beside this one: `stage` and `move` must then be safe to call from both).
std::vector<std::filesystem::path> WritePipelineOutputs(
    const PipelineResult& result, const PipelineReportOptions& report, const nlohmann::json& model_info,
    const std::filesystem::path& folder,
    const std::function<std::filesystem::path(const std::filesystem::path&)>& stage,
    const std::filesystem::path& work = {}, bool model_files_written = false,
    const std::function<void(const std::filesystem::path&, const std::filesystem::path&)>& move = {});

/// The files that need only the model, each written alone (PipelineRun::model_files), largest first:
/// model.h5, scores.csv, mean.ply, eigen.csv (as WriteModelFiles writes them), then the report's figures of
/// the model (ModelReportFigures). `model` must outlive them.
std::vector<OutputFile> ModelOutputFiles(const ShapeModel& model, const nlohmann::json& model_info,
                                         const PipelineReportOptions& report);

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
