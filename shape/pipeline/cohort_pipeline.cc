#include "shape/pipeline/cohort_pipeline.h"

#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <fstream>
#include <mutex>
#include <sstream>

#include "registration/generalised_procrustes.h"
#include "registration/kdtree.h"
#include "shape/core/atomic_file.h"
#include "shape/core/error.h"
#include "shape/core/number_format.h"
#include "shape/io/landmark_io.h"
#include "shape/io/mesh_io.h"
#include "shape/model/shape_grid.h"
#include "shape/pipeline/internal/subject_record.h"
#include "shape/surface/cloud_filter.h"

namespace pectus {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

double Since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

// True if `name` is `pattern` with its one '*' standing for any text.
bool Matches(const std::string& name, const std::string& pattern) {
  const std::size_t star = pattern.find('*');
  if (star == std::string::npos) return name == pattern;
  const std::string prefix = pattern.substr(0, star), suffix = pattern.substr(star + 1);
  return name.size() >= prefix.size() + suffix.size() && name.compare(0, prefix.size(), prefix) == 0 &&
         name.compare(name.size() - suffix.size(), suffix.size(), suffix) == 0;
}

// Runs one stage of one subject: times it, and turns an exception into the subject's failure.
template <class Fn>
bool RunStage(SubjectOutcome* s, const std::string& stage, Fn fn) {
  if (!s->failed_stage.empty()) return false;
  const Clock::time_point start = Clock::now();
  try {
    fn();
  } catch (const std::exception& e) {
    s->failed_stage = stage;
    s->error = e.what();
  }
  s->timings_s.Add(stage, Since(start));
  return s->failed_stage.empty();
}

// Read (and crop), merge and reconstruct one subject (stages 1-3).
void BuildSurface(const CohortSubject& in, const PipelineOptions& options, SubjectOutcome* s,
                  std::vector<PointCloud>* sweeps) {
  RunStage(s, "read", [&] {
    if (in.sweeps.empty()) ThrowBadInput(in.name, "has no sweep files");
    s->landmarks = ReadLandmarks(in.landmarks);
    const ChestRoi roi = ComputeChestRoi(s->landmarks, options.roi, in.landmarks.string());
    for (const fs::path& f : in.sweeps) {
      PointCloud sweep = ReadPointCloud(f);
      if (options.crop_margin_mm > 0.0) sweep = CropToRoi(sweep, roi, options.crop_margin_mm);
      if (sweep.size() < options.min_sweep_points) continue;
      sweeps->push_back(std::move(sweep));
      s->sweep_files.push_back(f);
    }
    s->sweeps = static_cast<int>(sweeps->size());
    if (sweeps->empty())
      ThrowBadInput(in.name, "no sweep has " + std::to_string(options.min_sweep_points) +
                                 " points within the region of interest of its landmarks");
  });
  SweepMergeResult merged;
  RunStage(s, "merge", [&] {
    merged = MergeSweeps(*sweeps, std::vector<Rigid3>(sweeps->size(), Rigid3::Identity()), options.merge);
    s->points_in = merged.points_in;
    s->points_merged = merged.points_out;
    s->merge_rms_mm = merged.global_rms_after_mm;
    s->T_subject_sweep = merged.T_world_sweep;
  });
  sweeps->clear();
  RunStage(s, "reconstruct", [&] {
    ReconstructResult r = ReconstructSurface(merged.merged, options.reconstruct, in.name);
    s->surface = std::move(r.mesh);
    s->faces = s->surface.num_faces();
    s->fit_accuracy_mm = r.accuracy.fitting_accuracy_mm;
    if (s->faces == 0) ThrowFailure("the reconstruction has no triangles", in.name);
  });
}

// Moves one subject's grid, surface, landmarks and ROI by T, and composes T into its pose.
void MoveSubject(const Similarity3& T, SubjectOutcome* s) {
  TransformInPlace(T, &s->grid.mesh);
  s->grid.shape_vector = ToShapeVector(s->grid.mesh.vertices.positions);
  s->grid.roi = s->grid.roi.Transformed(T);
  TransformInPlace(T, &s->surface);
  s->landmarks = s->landmarks.Transformed(T);
  s->measures.deepest_point = T * s->measures.deepest_point;
  s->T_reference_subject = T * s->T_reference_subject;
  s->T_aligned_registered = T * s->T_aligned_registered;
}

// Which grid vertices of each good subject count as seen: within `gap_mm` of its scan data ("scan_gap_mm",
// ResampleSubject); every vertex when imputation is off (gap_mm <= 0 or infinite).
Eigen::Matrix<bool, Eigen::Dynamic, Eigen::Dynamic> SeenVertices(const std::vector<int>& good, double gap_mm,
                                                                 const PipelineResult& result) {
  const Eigen::Index m = result.subjects[good[0]].grid.mesh.vertices.size();
  Eigen::Matrix<bool, Eigen::Dynamic, Eigen::Dynamic> seen(static_cast<Eigen::Index>(good.size()), m);
  seen.setConstant(true);
  if (!(gap_mm > 0.0) || !std::isfinite(gap_mm)) return seen;
  for (std::size_t k = 0; k < good.size(); ++k) {
    const auto& scalars = result.subjects[good[k]].grid.mesh.vertices.scalars;
    const auto gap = scalars.find("scan_gap_mm");
    if (gap == scalars.end()) continue;
    for (Eigen::Index v = 0; v < m; ++v) seen(static_cast<Eigen::Index>(k), v) = gap->second[v] <= gap_mm;
  }
  return seen;
}

// Generalized Procrustes analysis, rigid, of the grids (no reference: the mean floats with the grids);
// each subject moved with its grid. Only the vertices every subject saw are compared, when they are at
// least half of the grid (a vertex filled in one subject would otherwise pull every pose).
void AlignGridsToTheirMean(const std::vector<int>& good, int iterations,
                           const Eigen::Matrix<bool, Eigen::Dynamic, Eigen::Dynamic>& seen,
                           PipelineResult* result) {
  if (iterations <= 0) return;
  std::vector<Eigen::Index> common;
  for (Eigen::Index v = 0; v < seen.cols(); ++v)
    if (seen.col(v).all()) common.push_back(v);
  const bool subset = static_cast<Eigen::Index>(common.size()) < seen.cols() &&
                      2 * static_cast<Eigen::Index>(common.size()) >= seen.cols();
  std::vector<Points3> grids;
  std::vector<std::string> names;
  for (int i : good) {
    const Points3& all = result->subjects[i].grid.mesh.vertices.positions;
    grids.push_back(subset ? Points3(all(common, Eigen::all)) : all);
    names.push_back(result->subjects[i].name + " grid");
  }
  ProcrustesOptions o;
  o.reference.reset();
  o.max_iterations = iterations - 1;  // each grid aligned `iterations` times
  o.tolerance_mm = 0.0;
  o.min_spread_ratio = 0.0;
  const ProcrustesResult gpa = GeneralisedProcrustes(grids, o, names);
  for (std::size_t k = 0; k < good.size(); ++k) MoveSubject(gpa.T_mean_shape[k], &result->subjects[good[k]]);
}

// The good subjects' grids as shapes, N by 3m.
Eigen::MatrixXd ShapesOf(const std::vector<int>& good, const PipelineResult& result) {
  Eigen::MatrixXd shapes(static_cast<Eigen::Index>(good.size()),
                         result.subjects[good[0]].grid.shape_vector.size());
  for (std::size_t k = 0; k < good.size(); ++k) {
    shapes.row(static_cast<Eigen::Index>(k)) = result.subjects[good[k]].grid.shape_vector.transpose();
  }
  return shapes;
}

// Each subject's unseen grid vertices as filled from the other subjects (`filled`: ImputeMissingVertices);
// the grids take the fills and mark them ("filled_from_cohort": 1).
void TakeFills(const std::vector<int>& good, const Eigen::Matrix<bool, Eigen::Dynamic, Eigen::Dynamic>& seen,
               const ImputationResult& filled, PipelineResult* result) {
  for (std::size_t k = 0; k < good.size(); ++k) {
    SubjectOutcome& s = result->subjects[good[k]];
    const auto row = static_cast<Eigen::Index>(k);
    s.grid.shape_vector = filled.shapes.row(row).transpose();
    s.grid.mesh.vertices.positions = FromShapeVector(s.grid.shape_vector);
    Eigen::VectorXd mark(seen.cols());
    for (Eigen::Index v = 0; v < seen.cols(); ++v) mark[v] = seen(row, v) ? 0.0 : 1.0;
    const bool too_little = std::find(filled.too_little_seen.begin(), filled.too_little_seen.end(),
                                      static_cast<int>(k)) != filled.too_little_seen.end();
    if (too_little) mark.setZero();
    s.grid.mesh.vertices.scalars["filled_from_cohort"] = mark;
    s.vertices_filled_from_cohort = filled.filled_vertices[k];
    s.largest_fill_change_mm = filled.largest_change_mm[k];
  }
  result->imputation_message = filled.message;
}

// 7. The model of the subjects in `result` that made it: their grids aligned to their mean (Procrustes),
// unseen vertices filled, PCA, quality; their scores; the mean's measures (on the mean landmark ROI).
// A collective (every process calls it): the leader, which holds the subjects' grids, aligns them and
// hands their shapes to the others; all of them fill and model the shapes together (ImputeMissingVertices,
// BuildShapeModel); the leader keeps the model. `ready`: the leader's subjects are read back (false: its
// error is in `why` on every process, and nothing is modelled).
void BuildModel(const PipelineOptions& options, TaskRunner& runner, bool ready, std::string* why,
                PipelineResult* result) {
  const bool leader = runner.IsLeader();
  std::vector<int> good;
  Eigen::Matrix<bool, Eigen::Dynamic, Eigen::Dynamic> seen;
  Eigen::MatrixXd shapes;
  Clock::time_point start = Clock::now();
  if (leader && ready) {
    try {
      for (int i = 0; i < static_cast<int>(result->subjects.size()); ++i) {
        if (result->subjects[i].ok) good.push_back(i);
      }
      result->succeeded = static_cast<int>(good.size());
      if (good.size() >= 2) {
        const bool impute = static_cast<int>(good.size()) >= options.impute_min_subjects;
        seen = SeenVertices(good, impute ? options.impute_gap_mm : 0.0, *result);
        AlignGridsToTheirMean(good, options.procrustes_iterations, seen, result);
        shapes = ShapesOf(good, *result);
        result->timings_s.Add("model align", Since(start));
      }
    } catch (const std::exception& e) {
      ready = false;
      *why = e.what();
    }
  }
  if (!runner.BroadcastOutcome(ready, why)) ThrowFailure(*why);
  std::int64_t size[3] = {shapes.rows(), shapes.cols(), seen.cols()};
  runner.Broadcast(size, sizeof size);
  if (size[0] < 2) return;
  if (!leader) {
    shapes.resize(size[0], size[1]);
    seen.resize(size[0], size[2]);
  }
  runner.Broadcast(shapes.data(), shapes.size() * static_cast<std::int64_t>(sizeof(double)));
  runner.Broadcast(seen.data(), seen.size() * static_cast<std::int64_t>(sizeof(bool)));
  Clock::time_point step = Clock::now();
  if (!seen.all()) {
    ImputationResult filled =
        ImputeMissingVertices(shapes, seen, options.imputation, "resampled subjects", &runner);
    if (leader) TakeFills(good, seen, filled, result);
    shapes = std::move(filled.shapes);
  }
  if (leader) result->timings_s.Add("model impute", Since(step));
  step = Clock::now();
  ShapeModel model = BuildShapeModel(shapes, options.model, "resampled subjects", &runner);
  if (!leader) return;
  result->timings_s.Add("model pca", Since(step));
  result->model.emplace(std::move(model));
  for (int i : good) result->model->names.push_back(result->subjects[i].name);
  result->model->faces = GridFaces(options.resample.grid);
  for (std::size_t k = 0; k < good.size(); ++k) {
    result->subjects[good[k]].scores = result->model->scores.row(static_cast<Eigen::Index>(k)).transpose();
  }
  result->timings_s.Add("model", Since(start));
  if (options.quality && good.size() >= 3) {
    start = Clock::now();
    result->quality = EvaluateModelQuality(shapes, options.quality_options);
    result->timings_s.Add("quality", Since(start));
  }
  start = Clock::now();
  LandmarkSet mean_landmarks = result->subjects[good[0]].landmarks;
  for (Landmark& l : mean_landmarks.items) {
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    int count = 0;
    for (int i : good) {
      if (const Landmark* m = result->subjects[i].landmarks.Find(l.label)) sum += m->position, ++count;
    }
    l.position = sum / count;
  }
  try {
    result->mean_measures = MeasureChest(model.ToMesh(model.mean),
                                         ComputeChestRoi(mean_landmarks, options.roi, "mean landmarks"));
  } catch (const Error& e) {
    result->mean_measures.message = e.what();
  }
  result->timings_s.Add("mean measures", Since(start));
}

// The mean shape as a mesh record in the work folder, for the processes that compute the distances to it.
void WriteMeanRecord(const fs::path& work, const ShapeModel& model) {
  SubjectOutcome mean;
  mean.name = "mean shape";
  mean.surface = model.ToMesh(model.mean);
  internal::WriteSubjectRecord(work / "mean.rec", mean);
}

std::optional<TriangleMesh> ReadMeanRecord(const fs::path& work) {
  std::error_code ec;
  if (!fs::exists(work / "mean.rec", ec)) return std::nullopt;
  return std::move(internal::ReadSubjectRecord(work / "mean.rec").surface);
}

// The subjects' results of one phase ("surface": stages 1-3; "registered": 4-6): in memory, or one record
// per subject committed to `work/PHASE/NAME.rec` as it finishes (PipelineRun).
class SubjectStore {
 public:
  SubjectStore(const fs::path& work, const std::string& phase, const std::vector<CohortSubject>& subjects)
      : folder_(work.empty() ? fs::path() : work / phase), held_(subjects.size()) {
    for (const CohortSubject& s : subjects) names_.push_back(s.name);
  }
  bool Has(int i) const {
    std::error_code ec;
    return folder_.empty() ? held_[i].has_value() : fs::exists(Path(i), ec);
  }
  // The subjects without a result, in subject order.
  std::vector<int> Missing() const { return Missing(LargestFirst(std::vector<double>(names_.size(), 0.0))); }
  // The subjects of `order` without a result, in that order.
  std::vector<int> Missing(const std::vector<int>& order) const {
    std::vector<int> missing;
    for (int i : order) {
      if (!Has(i)) missing.push_back(i);
    }
    return missing;
  }
  void Put(int i, SubjectOutcome s) {
    if (folder_.empty()) {
      held_[i] = std::move(s);
    } else {
      internal::WriteSubjectRecord(Path(i), s);
    }
  }
  SubjectOutcome Get(int i) const {
    return folder_.empty() ? *held_[i] : internal::ReadSubjectRecord(Path(i));
  }
  // Get, releasing the one held in memory.
  SubjectOutcome Take(int i) {
    if (!folder_.empty()) return Get(i);
    SubjectOutcome s = std::move(*held_[i]);
    held_[i].reset();
    return s;
  }

 private:
  fs::path Path(int i) const { return folder_ / (names_[i] + ".rec"); }
  fs::path folder_;
  std::vector<std::string> names_;
  std::vector<std::optional<SubjectOutcome>> held_;
};

}  // namespace

PointCloud CropToRoi(const PointCloud& cloud, const ChestRoi& roi, double margin_mm) {
  const Points3 uvw = roi.ToRoi(cloud.positions);
  std::vector<std::uint32_t> rows;
  for (Eigen::Index k = 0; k < uvw.rows(); ++k) {
    if (uvw(k, 0) >= roi.u_min - margin_mm && uvw(k, 0) <= roi.u_max + margin_mm &&
        uvw(k, 1) >= roi.v_min - margin_mm && uvw(k, 1) <= roi.v_max + margin_mm) {
      rows.push_back(static_cast<std::uint32_t>(k));
    }
  }
  return SelectRows(cloud, rows);
}

void RegisterSubject(const IcpTarget& reference_surface, const LandmarkSet& reference_landmarks,
                     const PipelineOptions& options, SubjectOutcome* s) {
  const PairRegistrationResult r = RegisterPair(reference_surface, s->surface.vertices, &reference_landmarks,
                                                &s->landmarks, {}, options.registration);
  s->icp_rms_mm = r.icp ? r.icp->rms_mm : 0.0;
  s->icp_accepted = r.success && r.refined;
  s->T_reference_subject = r.T_target_source;
  s->landmark_rms_mm = r.landmark_rms_mm;
  s->registration_message = r.message;
  TransformInPlace(s->T_reference_subject, &s->surface);
  s->landmarks = s->landmarks.Transformed(s->T_reference_subject);
}

void ResampleSubject(const PipelineOptions& options, SubjectOutcome* s) {
  s->grid = ResampleSurface(s->surface, s->landmarks, options.roi, options.resample, s->name);
  // How far each grid vertex is from the scan's points: the resampler's gap to its profiles' data, or,
  // where the reconstruction filled a hole (its vertices' "data_distance", TrimToData), that distance.
  Eigen::VectorXd gap = s->grid.mesh.vertices.scalars.at("data_gap_mm");
  const auto surface_gap = s->surface.vertices.scalars.find("data_distance");
  if (surface_gap != s->surface.vertices.scalars.end() && s->surface.num_vertices() > 0) {
    const KdTree3 tree(s->surface.vertices.positions);
    const Points3& grid = s->grid.mesh.vertices.positions;
    for (Eigen::Index v = 0; v < grid.rows(); ++v) {
      std::uint32_t nearest = 0;
      double d2 = 0.0;
      if (tree.Nearest(grid.row(v).transpose(), &nearest, &d2)) {
        gap[v] = std::max(gap[v], surface_gap->second[nearest] - std::sqrt(d2));
      }
    }
  }
  s->grid.mesh.vertices.scalars["scan_gap_mm"] = gap;
}

std::vector<CohortSubject> FindCohortSubjects(const fs::path& folder, const std::string& sweep_pattern,
                                              const std::string& landmarks_name) {
  std::error_code ec;
  if (!fs::is_directory(folder, ec)) ThrowBadInput(folder.string(), "is not a folder");
  std::vector<CohortSubject> subjects;
  for (const fs::directory_entry& dir : fs::directory_iterator(folder, ec)) {
    if (!dir.is_directory()) continue;
    CohortSubject s;
    s.name = dir.path().filename().string();
    for (const fs::directory_entry& f : fs::directory_iterator(dir.path(), ec)) {
      if (f.is_regular_file() && Matches(f.path().filename().string(), sweep_pattern))
        s.sweeps.push_back(f.path());
    }
    if (s.sweeps.empty()) continue;
    std::sort(s.sweeps.begin(), s.sweeps.end());
    s.landmarks = dir.path() / landmarks_name;
    subjects.push_back(std::move(s));
  }
  if (ec) ThrowBadInput(folder.string(), "cannot be listed: " + ec.message());
  if (subjects.empty()) {
    ThrowBadInput(folder.string(), "holds no subject folder with sweeps named '" + sweep_pattern + "'");
  }
  std::sort(subjects.begin(), subjects.end(), [](const auto& a, const auto& b) { return a.name < b.name; });
  return subjects;
}

fs::path SubjectFilesFolder(const fs::path& work, const std::string& name) { return work / "files" / name; }

void RemoveSubjectResults(const fs::path& work) {
  std::error_code ec;
  for (const char* phase :
       {"surface", "registered", "grids", "model", "outputs", "files", "mean.rec", "picture_scale"}) {
    fs::remove_all(work / phase, ec);
    if (ec) ThrowFailure("cannot remove the subjects' results: " + ec.message(), (work / phase).string());
  }
  if (fs::is_empty(work, ec)) fs::remove(work, ec);
}

std::string PipelineResult::BriefReport() const {
  std::ostringstream s;
  s.precision(3);
  s << message;
  if (quality && quality->generalization_mm.size() > 0)
    s << "; generalization " << quality->generalization_mm[quality->generalization_mm.size() - 1] << " mm";
  s << "; " << timings_s.Total() << " s of work";
  return s.str();
}

bool PipelineOptions::IsValid(std::string* why) const {
  if (!merge.IsValid(why) || !reconstruct.IsValid(why) || !registration.IsValid(why) || !roi.IsValid(why) ||
      !resample.IsValid(why) || !model.IsValid(why) || !imputation.IsValid(why)) {
    return false;
  }
  if (!(crop_margin_mm >= 0.0) || min_sweep_points < 10 || procrustes_iterations < 0 ||
      std::isnan(impute_gap_mm) || impute_min_subjects < 3) {
    if (why != nullptr) {
      *why =
          "the crop margin must be >= 0 mm, a sweep needs at least 10 points, the Procrustes iterations "
          "must be >= 0, the imputation gap a number of mm and imputation needs at least 3 subjects";
    }
    return false;
  }
  return !quality || quality_options.IsValid(why);
}

PipelineResult RunCohortPipeline(const std::vector<CohortSubject>& inputs, const PipelineOptions& options,
                                 const PipelineObserver& observer, const PipelineRun& run) {
  std::string why;
  if (!options.IsValid(&why)) ThrowUsage("pipeline: " + why);
  const auto n = static_cast<int>(inputs.size());
  SerialTaskRunner serial;
  TaskRunner& runner = run.runner != nullptr ? *run.runner : serial;
  if (!run.resume && !run.work.empty() && runner.IsLeader()) RemoveSubjectResults(run.work);
  runner.Barrier();
  const bool in_memory = run.work.empty();
  if (in_memory && (run.subject_files || run.subject_pictures))
    ThrowUsage("pipeline: the subjects' output files are made in a work folder; none was given");
  SubjectStore surfaces(run.work, "surface", inputs), registered(run.work, "registered", inputs);
  SubjectStore grids(run.work, "grids", inputs);
  if (const std::vector<int> missing = registered.Missing(); run.gather && !missing.empty()) {
    std::vector<std::string> names;
    for (int i : missing) names.push_back(inputs[i].name);
    ThrowUsage("--gather: no share has finished subject(s) " + NamesForMessage(names) +
               " (their results are not in " + run.work.string() +
               "); run their shares, or the whole run with --resume");
  }
  // The subjects handed out largest first (bytes of sweeps), so that the last to finish are small ones.
  std::vector<double> bytes(inputs.size(), 0.0);
  for (std::size_t i = 0; i < inputs.size(); ++i) {
    std::error_code ec;
    for (const fs::path& f : inputs[i].sweeps) bytes[i] += static_cast<double>(fs::file_size(f, ec));
  }
  const std::vector<int> largest_first = LargestFirst(bytes);
  auto report = [&](const SubjectOutcome& s, const std::string& stage) {
    if (!observer) return;
#pragma omp critical(pectus_pipeline_observer)
    observer(s, stage);
  };

  // 1-3. Every subject's surface from its sweeps: read, merge, reconstruct (subjects in parallel).
  auto build_surface = [&](int i) {
    SubjectOutcome s;
    s.name = inputs[i].name;
    std::vector<PointCloud> sweeps;
    BuildSurface(inputs[i], options, &s, &sweeps);
    surfaces.Put(i, s);
    report(s, "surface");
  };
  runner.Run(surfaces.Missing(largest_first), build_surface);

  // 4. The reference: the named subject, or the first whose surface was made (made here if a share of a
  // job array did not make it).
  int ref = -1;
  for (int i = 0; i < n && ref < 0; ++i) {
    if (!options.reference.empty() && inputs[i].name != options.reference) continue;
    if (!surfaces.Has(i)) build_surface(i);
    if (!options.reference.empty() || surfaces.Get(i).failed_stage.empty()) ref = i;
  }
  if (ref < 0 && !options.reference.empty())
    ThrowUsage("pipeline: no subject is named '" + options.reference + "'");
  std::optional<SubjectOutcome> reference;
  if (ref >= 0) reference = surfaces.Get(ref);
  if (ref < 0 || !reference->failed_stage.empty()) {
    ThrowFailure(ref < 0 ? "no subject's surface could be made; nothing to register to"
                         : "the reference subject failed: " + reference->error,
                 ref < 0 ? "cohort" : inputs[ref].name);
  }
  PipelineResult result;
  result.reference = inputs[ref].name;
  const IcpTarget target(reference->surface.vertices.positions, reference->surface.vertices.normals,
                         reference->name + " (reference surface)");
  const LandmarkSet reference_landmarks = reference->landmarks;
  reference.reset();

  // 5-6. Register each surface to the reference (landmarks, then ICP), resample it on its landmark grid.
  runner.Run(registered.Missing(largest_first), [&](int i) {
    SubjectOutcome s = surfaces.Take(i);
    RunStage(&s, "register", [&] {
      if (i == ref) {
        s.icp_accepted = true;
        s.registration_message = "the reference";
        return;
      }
      RegisterSubject(target, reference_landmarks, options, &s);
    });
    RunStage(&s, "resample", [&] { ResampleSubject(options, &s); });
    if (options.measures) {
      RunStage(&s, "measures", [&] {
        try {
          s.measures = MeasureChest(s.surface, s.grid.roi);
        } catch (const Error& e) {
          s.measures.message = e.what();  // a surface without a measurable section is not a failure
        }
      });
    }
    s.ok = s.failed_stage.empty();
    if (!options.keep_surfaces) s.surface = TriangleMesh();
    if (!in_memory) {  // the subject without its surface, for the model (written first: `registered` commits)
      SubjectOutcome light = s;
      light.surface = TriangleMesh();
      grids.Put(i, light);
    }
    registered.Put(i, s);
    report(s, "resample");
  });
  if (run.subjects_only) return result;

  // 7. The model of the subjects that made it, on the leader, from their grids read back one by one in
  // subject order (with a work folder, without their surfaces: they are not all held at once). Each
  // subject's part of it (alignment, fills, scores) is committed for the third task, with the mean.
  SubjectStore modelled(run.work, "model", inputs), finished(run.work, "outputs", inputs);
  std::exception_ptr model_error;
  {
    // The leader reads the grids back while the other processes wait: it takes their cores meanwhile (the
    // bytes do not depend on it); then they model together (BuildModel).
    const int threads = omp_get_max_threads();
    bool ready = true;
    std::string not_ready;
    if (runner.IsLeader()) {
      omp_set_num_threads(runner.SerialThreads());
      try {
        const Clock::time_point start = Clock::now();
        result.subjects.reserve(inputs.size());
        for (int i = 0; i < n; ++i) result.subjects.push_back(in_memory ? registered.Take(i) : grids.Get(i));
        result.timings_s.Add("read back", Since(start));
      } catch (const std::exception& e) {
        ready = false;
        not_ready = e.what();
      }
      omp_set_num_threads(threads);
    }
    try {
      BuildModel(options, runner, ready, &not_ready, &result);
    } catch (...) {
      if (runner.IsLeader()) model_error = std::current_exception();  // the leader reports it, below
    }
  }
  if (runner.IsLeader() && !model_error) {
    const int threads = omp_get_max_threads();
    omp_set_num_threads(runner.SerialThreads());
    try {
      Clock::time_point start = Clock::now();
      if (!in_memory) {
        std::error_code ec;
        fs::remove_all(run.work / "model", ec);
        for (int i = 0; i < n; ++i) {
          if (result.subjects[i].ok && result.model) modelled.Put(i, result.subjects[i]);
        }
        if (result.model) WriteMeanRecord(run.work, *result.model);
      }
      result.timings_s.Add("model records", Since(start));
    } catch (...) {
      model_error = std::current_exception();
    }
    omp_set_num_threads(threads);
  }
  // The mean, once per process, for the third task (read from the work folder on other processes).
  std::once_flag mean_once;
  std::optional<TriangleMesh> mean;
  auto the_mean = [&]() -> const std::optional<TriangleMesh>& {
    std::call_once(mean_once, [&] {
      if (runner.IsLeader() && result.model) {
        mean = result.model->ToMesh(result.model->mean);
      } else if (!in_memory) {
        mean = ReadMeanRecord(run.work);
      }
    });
    return mean;
  };

  // 8. Each subject's distance to the mean, then its output files (subjects in parallel, on the farm).
  auto finish = [&](int i) {
    SubjectOutcome s;
    if (in_memory) {
      s = std::move(result.subjects[i]);
    } else {
      s = registered.Get(i);  // with its surface, as registered
      if (modelled.Has(i)) {
        SubjectOutcome m = modelled.Get(i);
        TransformInPlace(m.T_aligned_registered, &s.surface);
        m.surface = std::move(s.surface);
        s = std::move(m);
      }
    }
    if (s.ok && the_mean()) {
      const Clock::time_point start = Clock::now();
      s.to_mean =
          ComputeDistanceMap(s.grid.mesh.vertices.positions, *the_mean(), options.distance, "mean shape");
      s.timings_s.Add("distance", Since(start));
    }
    if (run.subject_files) {
      const Clock::time_point start = Clock::now();
      const fs::path folder = SubjectFilesFolder(run.work, s.name);
      fs::create_directories(folder);
      run.subject_files(s, folder);
      s.timings_s.Add("files", Since(start));
    }
    if (in_memory) {
      result.subjects[i] = std::move(s);
    } else {
      s.surface = TriangleMesh();
      finished.Put(i, s);  // commits the subject's third task
    }
  };
  const std::vector<int> no_tasks;
  runner.Run(model_error ? no_tasks : finished.Missing(largest_first), finish);
  if (runner.IsLeader() && !in_memory && !model_error) {
    const Clock::time_point start = Clock::now();
    for (int i = 0; i < n; ++i) result.subjects[i] = finished.Get(i);
    result.timings_s.Add("read back", Since(start));
  }

  // 9. The files that need every subject's distances (the report's maps on one colour scale), on the farm.
  if (run.subject_pictures) {
    const fs::path scale_path = run.work / "picture_scale";
    if (runner.IsLeader() && !model_error) {
      try {
        const double scale = run.picture_scale ? run.picture_scale(result.subjects) : 0.0;
        WriteFileAtomically(scale_path, ExactText(scale));
      } catch (...) {
        model_error = std::current_exception();  // thrown below, once the other processes are let go
      }
    }
    std::once_flag scale_once;
    double scale = 0.0;
    std::mutex seconds_mutex;
    double seconds = 0.0;  // this process's part
    runner.Run(model_error ? no_tasks : largest_first, [&](int i) {
      const Clock::time_point start = Clock::now();
      std::call_once(scale_once, [&] { scale = ReadExactText(scale_path.string()); });
      const SubjectOutcome s = in_memory ? result.subjects[i] : finished.Get(i);
      run.subject_pictures(s, scale, SubjectFilesFolder(run.work, s.name));
      const std::lock_guard<std::mutex> lock(seconds_mutex);
      seconds += Since(start);
    });
    result.timings_s.Add("pictures", seconds);
  }
  if (model_error) std::rethrow_exception(model_error);
  if (!runner.IsLeader()) return result;
  Timings subjects;
  for (const SubjectOutcome& s : result.subjects) subjects.Add(s.timings_s);
  subjects.Add(result.timings_s);
  result.timings_s = std::move(subjects);
  std::ostringstream msg;
  msg << result.succeeded << " of " << n << " subjects made it to the model (reference " << result.reference
      << ")";
  if (result.model) msg << "; " << result.model->num_modes() << " modes";
  result.message = msg.str();
  return result;
}

}  // namespace pectus
