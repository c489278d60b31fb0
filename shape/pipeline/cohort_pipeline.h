// pectus: the main job, from a folder of raw subjects (handheld sweeps + landmarks) to the average chest:
// per subject merge the sweeps, reconstruct the surface, register it to the reference by landmarks then
// ICP, resample it by cross-sections; then the shape model, its quality, and each subject's distance to
// the mean (dissertation §4.3.1). A subject that fails is reported and the others go on.
#pragma once

#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "registration/register_pair.h"
#include "shape/core/geometry.h"
#include "shape/core/landmarks.h"
#include "shape/core/task_runner.h"
#include "shape/core/timings.h"
#include "shape/model/compute_chest_roi.h"
#include "shape/model/cross_section_resampler.h"
#include "shape/model/distance_map.h"
#include "shape/model/impute_missing_vertices.h"
#include "shape/model/measure_chest.h"
#include "shape/model/model_quality.h"
#include "shape/model/shape_model.h"
#include "shape/surface/merge_sweeps.h"
#include "shape/surface/reconstruct_surface.h"

namespace pectus {

/// One subject's raw data.
struct CohortSubject {
  std::string name;                           ///< the folder's name
  std::vector<std::filesystem::path> sweeps;  ///< PLY (or any point format) files, scanner frame, mm
  std::filesystem::path landmarks;            ///< .mrk.json (or .fcsv/.csv) in the same frame
};

/// The subjects of a cohort folder: every sub-folder holding files named `sweep_pattern` (a prefix and
/// suffix around one '*', e.g. "sweep_*.ply"), with its landmarks `landmarks_name` (checked when the subject
/// is processed, so that a missing file fails that subject only). Sorted by name. Throws Error(kBadInput)
/// naming the folder if it does not exist or holds no subject.
std::vector<CohortSubject> FindCohortSubjects(const std::filesystem::path& folder,
                                              const std::string& sweep_pattern = "sweep_*.ply",
                                              const std::string& landmarks_name = "landmarks.mrk.json");

/// Options of every stage.
struct PipelineOptions {
  /// Each sweep is cut to the ROI (from the subject's landmarks) widened by this margin (mm) before
  /// anything else: the model needs no more, and merging and reconstructing the whole torso would cost
  /// three times as long. 0: keep whole sweeps. At least fit_margin_mm of the resampling, for its profiles.
  double crop_margin_mm = 30.0;
  /// Sweeps left with fewer points than this after the cut (strips at the sides) are dropped.
  int min_sweep_points = 1000;
  SweepMergeOptions merge = [] {
    SweepMergeOptions o;
    o.target_spacing_mm = 1.0;  // 2 mm doubled the surface's error on data (0.13 vs 0.05-0.07 mm RMS)
    o.pairwise.auto_level_points = {2000};  // sweeps start within the tracker's error of each other
    o.pairwise.auto_max_iterations = 20;
    o.global_rounds = 6;
    return o;
  }();
  ReconstructOptions reconstruct = [] {
    ReconstructOptions o;
    o.spacing_mm = 1.0;  // isosurface step (mm), as fine as the merged cloud
    o.check = false;     // the CGAL manifold check costs as much as the rest; `pectus reconstruct` has it
    return o;
  }();
  /// Landmarks then ICP, to the reference subject. Two chests differ by millimetres (a depression by
  /// centimetres), so ICP may slide longer before it settles and its acceptance is wider than for two
  /// scans of one surface; the robust loss and the shrinking gate keep it on the parts that agree. The
  /// ICP refinement is kept only if it succeeds and makes the landmarks' RMS distance to the reference's
  /// at most 5 mm worse than the landmark fit's; otherwise the landmark pose is kept and the subject is
  /// flagged (SubjectOutcome::icp_accepted). RegisterPair decides it (fall_back_to_landmarks).
  PairRegistrationOptions registration = [] {
    PairRegistrationOptions o;
    o.max_landmark_rms_mm = 0.0;  // off: two chests' landmarks differ by centimetres
    o.max_landmark_rms_increase_mm = 5.0;
    o.fall_back_to_landmarks = true;
    o.icp.auto_max_iterations = 60;
    o.icp.rotation_tolerance_deg = 1e-2;
    o.icp.translation_tolerance_mm = 1e-2;
    o.icp.max_rms_mm = 5.0;
    o.icp.min_inlier_fraction = 0.1;
    return o;
  }();
  ChestRoiOptions roi;           ///< landmarks and margins that bound the grid
  CrossSectionOptions resample;  ///< grid size (51 x 101) and profile fit
  /// Before the model, the resampled grids are aligned rigidly to their mean (generalized Procrustes
  /// analysis, GeneralisedProcrustes with no reference: every grid aligned `procrustes_iterations` times,
  /// to means updated in between; 0: off). The registration to one reference subject leaves
  /// each grid a pose that is not shape (ICP between two different chests may slide by millimetres); the
  /// surfaces, landmarks and T_reference_subject follow their grid.
  int procrustes_iterations = 5;
  /// Grid vertices farther than this from the subject's scan points (the grid's "scan_gap_mm": the
  /// resampler's gap to its profiles' data, or the reconstruction's distance to data where it filled a
  /// hole; mm) are filled from the other subjects before the model is built (ImputeMissingVertices, at
  /// least 3 subjects): the surface and the resampler continue a subject's skin over its holes and past
  /// its data, which is good inside small holes and millimetres off over a wide occlusion, above all where
  /// it reaches the grid's border.
  /// The default is about two grid spacings (the resampler's "supported" distance); <= 0 or infinity: off.
  double impute_gap_mm = 6.0;
  /// ... when at least this many subjects made it (>= 3): the others' model of a smaller cohort has too
  /// few modes to predict a hole (on the 3-subject test cohort its fill was 4.9 mm off where the
  /// subject's own continuation was 2.5 mm off).
  int impute_min_subjects = 6;
  ImputationOptions imputation;
  ShapeModelOptions model;
  bool quality = true;  ///< compute compactness, generalization, specificity (N >= 3)
  ModelQualityOptions quality_options;
  DistanceKind distance = DistanceKind::kSignedSurface;  ///< each subject's grid to the mean grid
  bool measures = true;                                  ///< depression depth of each registered surface
  std::string reference;      ///< the reference subject's name; empty: the first that reconstructs
  bool keep_surfaces = true;  ///< keep each registered surface in the result (for output files)

  /// False, with the reason, for invalid options of any stage.
  bool IsValid(std::string* why) const;
};

/// What happened to one subject.
struct SubjectOutcome {
  std::string name;
  bool ok = false;           ///< went through every stage
  std::string failed_stage;  ///< "read", "merge", "reconstruct", "register", "resample" when not ok
  std::string error;         ///< why it failed
  int sweeps = 0;            ///< sweeps merged (after dropping those outside the ROI)
  /// The sweeps merged, and where the merge placed each: x_subject = T_subject_sweep[i] x_sweep (mm), in
  /// the subject's scan frame (the tracker's frame with a tracker prior; the first sweep's frame without).
  std::vector<std::filesystem::path> sweep_files;
  std::vector<Rigid3> T_subject_sweep;
  std::int64_t points_in = 0, points_merged = 0;
  double merge_rms_mm = 0.0;        ///< joint pose adjustment residual
  std::int64_t faces = 0;           ///< of the reconstructed surface
  double fit_accuracy_mm = 0.0;     ///< RBF fitting accuracy (dissertation Eq. 11)
  Similarity3 T_reference_subject;  ///< subject scan frame to the reference's
  /// The model stage's rigid alignment of the registered subject to the grids' mean (Procrustes), already
  /// composed into T_reference_subject; identity before the model stage.
  Similarity3 T_aligned_registered;
  double landmark_rms_mm = 0.0, icp_rms_mm = 0.0;
  bool icp_accepted = false;         ///< the ICP refinement was kept (else the landmark pose)
  std::string registration_message;  ///< what the fine step found, and why it was not kept
  TriangleMesh surface;              ///< the reconstructed surface in the reference frame (keep_surfaces)
  LandmarkSet landmarks;             ///< in the reference frame
  CrossSectionResult grid;           ///< the resampled grid (shape vector) in the reference frame
  ChestMeasures measures;            ///< when options.measures (depth 0 and a message if it failed)
  DistanceMapResult to_mean;         ///< distances of the grid vertices to the mean shape, mm
  Eigen::VectorXd scores;            ///< model scores (mm)
  /// Grid vertices farther than PipelineOptions::impute_gap_mm from the data, filled from the other
  /// subjects (marked "filled_from_cohort" on the grid), and the largest move of one by that fill (mm).
  int vertices_filled_from_cohort = 0;
  double largest_fill_change_mm = 0.0;
  Timings timings_s;  ///< wall time per stage (s): "read", "merge", ..., "measures"
};

/// The whole cohort's result.
struct PipelineResult {
  std::vector<SubjectOutcome> subjects;  ///< in input order, failed ones included
  std::string reference;                 ///< the reference subject's name
  int succeeded = 0;
  std::optional<ShapeModel> model;            ///< when at least 2 subjects made it; names = theirs
  std::optional<ModelQualityCurves> quality;  ///< when options.quality and at least 3 made it
  ChestMeasures mean_measures;                ///< of the mean shape (its grid)
  std::string imputation_message;  ///< what the fill of unseen vertices did (empty: nothing unseen)
  /// Wall time (s) per stage: the subjects' stages summed over subjects, then "model", "quality", "distance".
  Timings timings_s;
  std::string message;

  /// One line for a log: how many subjects made it, the reference, the modes, the wall time.
  std::string BriefReport() const;
};

/// The points of `cloud` whose ROI coordinates (u, v) lie within `margin_mm` of the ROI rectangle, with
/// their attributes.
PointCloud CropToRoi(const PointCloud& cloud, const ChestRoi& roi, double margin_mm);

/// Stage 5 for one subject, as the pipeline does it: RegisterPair of its surface and landmarks to the
/// reference's with options.registration (which decides whether the ICP refinement is kept). Sets the
/// subject's pose, registration figures and message, and moves its surface and landmarks into the
/// reference frame. Throws as RegisterPair (unusable landmarks).
void RegisterSubject(const IcpTarget& reference_surface, const LandmarkSet& reference_landmarks,
                     const PipelineOptions& options, SubjectOutcome* subject);

/// Stage 6 for one subject, as the pipeline does it: its registered surface resampled on the grid of its
/// landmarks' ROI (ResampleSurface with options.roi and options.resample) into subject->grid, whose
/// vertices get "scan_gap_mm": the larger of the resampler's "data_gap_mm" and the surface's
/// "data_distance" (TrimToData) at the nearest surface vertex.
void ResampleSubject(const PipelineOptions& options, SubjectOutcome* subject);

/// Called after each subject's stage ("merge", "register", ...), for progress and logs; may be empty.
using PipelineObserver = std::function<void(const SubjectOutcome& subject, const std::string& stage)>;

/// Where the subjects' stages run and where their results are kept (docs/cluster.md). Each subject goes
/// through two tasks, its surface (stages 1-3) and its registration and grid (5-6, after the reference is
/// known), each committing the subject's result as one file when it finishes; the model is then built by
/// every process together from those files, in blocks of subjects fixed by their number, without the
/// subjects' surfaces (with a work folder), and each subject goes through a third task: its distances to
/// the mean and its output files (`subject_files`), then, once every subject's distances are known, a
/// fourth: its files that depend on all of them (`subject_pictures`); both run while the leader
/// decomposes the model's Gram matrix. So the outputs are the same bytes whatever ran where.
/// One output file that a task makes alone: its path relative to the output folder, and how to write it
/// (atomically) to a given path.
struct OutputFile {
  std::filesystem::path path;
  std::function<void(const std::filesystem::path& to)> write;
};

struct PipelineRun {
  /// Runs the subjects' tasks; nullptr: SerialTaskRunner (this process's threads).
  TaskRunner* runner = nullptr;
  /// Folder of the subjects' results (`surface/NAME.rec`, `registered/NAME.rec`), on a file system every
  /// process sees; empty: kept in memory (one process only).
  std::filesystem::path work;
  /// Keep the results already in `work` and compute only the missing ones (a killed run, shards to
  /// gather); false: `work` is emptied first. The options and inputs must be those of the run that wrote
  /// them.
  bool resume = false;
  /// Stop after the subjects' results (a share of a job array, gathered later): no model.
  bool subjects_only = false;
  /// Every subject's results must be in `work` already (the shares' gather): Error(kUsage) naming those
  /// missing instead of computing them here.
  bool gather = false;
  /// Writes one subject's output files into `folder`, at their paths relative to the output folder, in the
  /// third task (after the model): called with the subject's whole outcome (its surface aligned with its
  /// grid, its distances to the mean), on whichever process runs the task. The files stay in
  /// `work/files/NAME/` for the leader to move into the outputs (SubjectFilesFolder). Needs `work`;
  /// empty: none.
  std::function<void(const SubjectOutcome& subject, const std::filesystem::path& folder)> subject_files;
  /// Once every subject's distances are known: one number every fourth task gets (the colour scale of the
  /// report's distance maps), from the subjects' summaries (their figures without the arrays: a distance
  /// map's statistics, not its distances; `ok` for a resampled subject, not its grid). It must be the largest
  /// of the numbers it gives for parts of the cohort (a maximum over subjects, as DistanceMapRange): it is
  /// called on blocks of subjects, shared among the processes, and the blocks' largest is taken.
  std::function<double(const std::vector<SubjectOutcome>& subjects)> picture_scale;
  /// The fourth task: one subject's files that need `scale` (its picture on the common scale), written
  /// into `folder` as subject_files does. Empty: none.
  std::function<void(const SubjectOutcome& subject, double scale, const std::filesystem::path& folder)>
      subject_pictures;
  /// The files that need only the model (its own files, the report's figures of it), listed from the
  /// result as every process has it after the model (its model, reference and count of subjects: the same
  /// list on every process), largest first. Each is written by one task of the farm, after the fourth
  /// tasks, into `work/model_files/PATH` (ModelFilesFolder) for the leader to move into the outputs. Needs
  /// `work`; empty: none (the caller writes them).
  std::function<std::vector<OutputFile>(const PipelineResult& result)> model_files;
};

/// The folder of the files written by PipelineRun::model_files, at their paths relative to the outputs.
std::filesystem::path ModelFilesFolder(const std::filesystem::path& work);

/// The folder of subject `name`'s files written by PipelineRun::subject_files and subject_pictures.
std::filesystem::path SubjectFilesFolder(const std::filesystem::path& work, const std::string& name);

/// Removes the subjects' results that RunCohortPipeline kept in `work` (its sub-folders), and `work`
/// itself if that leaves it empty. Nothing else in `work` is touched.
void RemoveSubjectResults(const std::filesystem::path& work);

/// RemoveSubjectResults shared among the runner's processes (a collective, every process calls it with the
/// subjects' names in the run's order): each removes the files of a block of subjects, the leader then the
/// rest. `remove` is the leader's word for every process (false: everything is kept, e.g. for --resume
/// after a failure). Returns the seconds it took on this process (0 when nothing was removed).
double RemoveSubjectResultsOnFarm(TaskRunner& runner, const std::filesystem::path& work,
                                  const std::vector<std::string>& names, bool remove);

/// Runs the pipeline. Throws Error(kUsage) for invalid options or an unknown reference name, and
/// Error(kFailure) if no subject reconstructs (nothing to register to); a failing subject never throws.
/// Only the runner's leader returns the whole result; other processes (and `subjects_only`) return the
/// reference's name and an empty list of subjects. With a work folder the leader's subjects have no
/// surface (they are not all held at once: `subject_files` gets each one's); without one they keep it
/// (PipelineOptions::keep_surfaces).
PipelineResult RunCohortPipeline(const std::vector<CohortSubject>& subjects,
                                 const PipelineOptions& options = {}, const PipelineObserver& observer = {},
                                 const PipelineRun& run = {});

}  // namespace pectus
