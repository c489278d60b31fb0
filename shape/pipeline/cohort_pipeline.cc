#include "shape/pipeline/cohort_pipeline.h"

#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <fstream>
#include <future>
#include <mutex>
#include <numeric>
#include <sstream>

#include "registration/generalised_procrustes.h"
#include "registration/kdtree.h"
#include "shape/core/atomic_file.h"
#include "shape/core/error.h"
#include "shape/core/timings.h"
#include "shape/io/landmark_io.h"
#include "shape/io/mesh_io.h"
#include "shape/model/shape_grid.h"
#include "shape/pipeline/internal/subject_record.h"
#include "shape/surface/cloud_filter.h"

namespace pectus {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

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
  s->timings_s.Add(stage, SecondsSince(start));
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

// 7. The model of the subjects that made it: their grids aligned to their mean (Procrustes), unseen
// vertices filled, PCA, quality; their scores; the mean's measures (on the mean landmark ROI). A collective
// (every process calls it alike): the subjects, in blocks fixed by their number, are shared among the
// processes at each step: their grids read (`light`: subject i as registered and resampled, without its
// surface), aligned, filled, modelled, and each one's part of the model kept (`keep`: subject i aligned,
// filled and scored, for the third task); the leader decomposes the Gram matrix and keeps the model. Sums
// over subjects add the blocks' parts in block order, so the bytes do not depend on the processes. `light`
// and `keep` are called from any process's threads.
void BuildModel(const PipelineOptions& options, TaskRunner& runner, const std::vector<std::string>& names,
                const std::function<SubjectOutcome(int)>& light,
                const std::function<void(int, SubjectOutcome)>& keep, std::optional<TriangleMesh>* mean,
                const std::function<void()>& while_decomposing, PipelineResult* result) {
  using RowMajor = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
  const bool leader = runner.IsLeader();
  const auto n = static_cast<std::int64_t>(names.size());
  const Eigen::Index m = options.resample.grid.num_vertices();
  const std::int64_t per_block = BlockRows(n, 8);
  const std::int64_t blocks = (n + per_block - 1) / per_block;
  auto rows_of = [&](int b) { return std::make_pair(b * per_block, std::min(n, (b + 1) * per_block)); };
  auto timed = [&](const char* step, Clock::time_point since) {
    if (leader) result->timings_s.Add(step, SecondsSince(since));
  };
  const double gap_mm = options.impute_gap_mm;
  const bool gaps = gap_mm > 0.0 && std::isfinite(gap_mm);

  // Each subject's row: made it (1/0), its grid's shape vector (3m), its vertices seen (1/0: within
  // impute_gap_mm of its scan data, "scan_gap_mm", ResampleSubject; every vertex without gaps).
  Clock::time_point start = Clock::now();
  const Eigen::Index width = 1 + 4 * m;
  RowMajor table(n, width);
  runner.ComputeBlocks(
      BlockOffsets(n, per_block, width),
      [&](int b, double* out) {
        const auto [first, end] = rows_of(b);
        for (std::int64_t i = first; i < end; ++i) {
          Eigen::Map<Eigen::RowVectorXd> row(out + (i - first) * width, width);
          row.setZero();
          const SubjectOutcome s = light(static_cast<int>(i));
          if (!s.ok) continue;
          const Points3& grid = s.grid.mesh.vertices.positions;
          if (grid.rows() != m) {
            ThrowBadInput(s.name, "has a grid of " + std::to_string(grid.rows()) +
                                      " vertices; the pipeline's has " + std::to_string(m));
          }
          row[0] = 1.0;
          row.segment(1, 3 * m) = ToShapeVector(grid).transpose();
          const auto gap = s.grid.mesh.vertices.scalars.find("scan_gap_mm");
          for (Eigen::Index v = 0; v < m; ++v) {
            row[1 + 3 * m + v] =
                !gaps || gap == s.grid.mesh.vertices.scalars.end() || gap->second[v] <= gap_mm;
          }
        }
      },
      table.data());
  std::vector<int> good;
  for (std::int64_t i = 0; i < n; ++i) {
    if (table(i, 0) == 1.0) good.push_back(static_cast<int>(i));
  }
  result->succeeded = static_cast<int>(good.size());
  timed("model read", start);
  if (good.size() < 2) return;
  const auto count = static_cast<Eigen::Index>(good.size());
  const bool impute = static_cast<int>(good.size()) >= options.impute_min_subjects;
  Eigen::Matrix<bool, Eigen::Dynamic, Eigen::Dynamic> seen(count, m);
  seen.setConstant(true);
  if (impute) {
    for (Eigen::Index k = 0; k < count; ++k) seen.row(k) = table.row(good[k]).tail(m).array() != 0.0;
  }

  // Generalized Procrustes analysis, rigid, of the grids (no reference: the mean floats with the grids).
  // Only the vertices every subject saw are compared, when they are at least half of the grid (a vertex
  // filled in one subject would otherwise pull every pose).
  start = Clock::now();
  std::vector<Similarity3> T(good.size());
  if (options.procrustes_iterations > 0) {
    std::vector<Eigen::Index> common;
    for (Eigen::Index v = 0; v < m; ++v)
      if (seen.col(v).all()) common.push_back(v);
    const bool subset =
        static_cast<Eigen::Index>(common.size()) < m && 2 * static_cast<Eigen::Index>(common.size()) >= m;
    std::vector<Points3> grids;
    std::vector<std::string> grid_names;
    for (int i : good) {
      const Points3 all = FromShapeVector(table.row(i).segment(1, 3 * m).transpose());
      grids.push_back(subset ? Points3(all(common, Eigen::all)) : all);
      grid_names.push_back(names[i] + " grid");
    }
    ProcrustesOptions o;
    o.reference.reset();
    o.max_iterations = options.procrustes_iterations - 1;  // each grid aligned `iterations` times
    o.tolerance_mm = 0.0;
    o.min_spread_ratio = 0.0;
    T = GeneralisedProcrustes(grids, o, grid_names, &runner).T_mean_shape;
  }
  timed("model align", start);
  // The aligned shapes, N by 3m (column-major, as the model takes them), in blocks of vertices: a block is a
  // run of columns.
  start = Clock::now();
  Eigen::MatrixXd shapes(count, 3 * m);
  const Eigen::Index per_vertices = BlockRows(m, 64);
  runner.ComputeBlocks(
      BlockOffsets(m, per_vertices, 3 * count),
      [&](int b, double* out) {
        const Eigen::Index first = b * per_vertices, vertices = std::min(m, first + per_vertices) - first;
        Eigen::Map<Eigen::MatrixXd> block(out, count, 3 * vertices);
        for (Eigen::Index k = 0; k < count; ++k) {
          const Eigen::Matrix3d A = T[k].scale * T[k].rotation;
          const double* x = table.data() + good[k] * width + 1 + 3 * first;
          for (Eigen::Index v = 0; v < vertices; ++v) {
            const Eigen::Vector3d y = A * Eigen::Map<const Eigen::Vector3d>(x + 3 * v) + T[k].translation;
            block(k, 3 * v) = y[0], block(k, 3 * v + 1) = y[1], block(k, 3 * v + 2) = y[2];
          }
        }
      },
      shapes.data());
  table.resize(0, 0);
  timed("model align", start);

  start = Clock::now();
  std::optional<ImputationResult> filled;
  if (!seen.all()) {
    filled = ImputeMissingVertices(shapes, seen, options.imputation, "resampled subjects", &runner);
    shapes = std::move(filled->shapes);
    if (leader) result->imputation_message = filled->message;
  }
  timed("model impute", start);

  // Each subject's part: aligned with its grid (MoveSubject), its fills marked ("filled_from_cohort": 1);
  // each block's sums of its subjects' landmarks (by the first subject's labels) for the mean's.
  start = Clock::now();
  std::vector<int> k_of(static_cast<std::size_t>(n), -1);
  for (std::size_t k = 0; k < good.size(); ++k) k_of[good[k]] = static_cast<int>(k);
  std::vector<std::string> labels;
  for (const Landmark& l : light(good[0]).landmarks.items) labels.push_back(l.label);
  const auto L = static_cast<std::int64_t>(labels.size());
  std::vector<double> landmark_sums(static_cast<std::size_t>(blocks * 4 * L));
  runner.ComputeBlocks(
      BlockOffsets(blocks, 1, 4 * L),
      [&](int b, double* out) {
        std::fill(out, out + 4 * L, 0.0);
        const auto [first, end] = rows_of(b);
        for (std::int64_t i = first; i < end; ++i) {
          const int k = k_of[i];
          if (k < 0) continue;
          SubjectOutcome s = light(static_cast<int>(i));
          MoveSubject(T[k], &s);
          s.grid.shape_vector = shapes.row(k).transpose();  // aligned as the model has it, and filled
          s.grid.mesh.vertices.positions = FromShapeVector(s.grid.shape_vector);
          if (filled) {
            Eigen::VectorXd mark = (!seen.row(k).array()).cast<double>().transpose();
            if (std::find(filled->too_little_seen.begin(), filled->too_little_seen.end(), k) !=
                filled->too_little_seen.end()) {
              mark.setZero();
            }
            s.grid.mesh.vertices.scalars["filled_from_cohort"] = mark;
            s.vertices_filled_from_cohort = filled->filled_vertices[k];
            s.largest_fill_change_mm = filled->largest_change_mm[k];
          }
          for (std::int64_t j = 0; j < L; ++j) {
            if (const Landmark* l = s.landmarks.Find(labels[j])) {
              Eigen::Map<Eigen::Vector3d>(out + 4 * j) += l->position;
              out[4 * j + 3] += 1.0;
            }
          }
          keep(static_cast<int>(i), std::move(s));
        }
      },
      landmark_sums.data());
  timed("model records", start);

  // The mean (as BuildShapeModel has it) for the subjects' third tasks, which run (while_decomposing) while
  // the leader decomposes the Gram matrix; then the model, its scores on every process.
  *mean = TriangleMesh();
  (*mean)->vertices.positions = FromShapeVector(shapes.colwise().mean().transpose());
  (*mean)->faces = GridFaces(options.resample.grid);
  start = Clock::now();
  double while_seconds = 0.0, eig_seconds = 0.0;
  ShapeModel model = BuildShapeModel(
      shapes, options.model, "resampled subjects", &runner,
      [&] {
        const Clock::time_point begin = Clock::now();
        while_decomposing();
        while_seconds = SecondsSince(begin);
      },
      &eig_seconds);
  if (leader) {
    result->timings_s.Add("model pca", SecondsSince(start) - std::max(while_seconds, eig_seconds));
    result->timings_s.Add("model eig", eig_seconds);
    for (std::size_t k = 0; k < good.size(); ++k)
      result->subjects[good[k]].scores = model.scores.row(k).transpose();
  }
  for (int i : good) model.names.push_back(names[i]);
  model.faces = GridFaces(options.resample.grid);
  if (!leader) {  // every process holds the model, for the files made of it alone (PipelineRun::model_files)
    result->model.emplace(std::move(model));
    return;
  }
  if (options.quality && good.size() >= 3) {
    start = Clock::now();
    result->quality = EvaluateModelQuality(shapes, options.quality_options);
    result->timings_s.Add("quality", SecondsSince(start));
  }
  start = Clock::now();
  LandmarkSet mean_landmarks;
  for (std::int64_t j = 0; j < L; ++j) {
    Eigen::Vector4d sum = Eigen::Vector4d::Zero();
    for (std::int64_t b = 0; b < blocks; ++b)
      sum += Eigen::Map<const Eigen::Vector4d>(&landmark_sums[(b * L + j) * 4]);
    mean_landmarks.items.push_back({labels[j], sum.head<3>() / sum[3], ""});
  }
  try {
    result->mean_measures = MeasureChest(model.ToMesh(model.mean),
                                         ComputeChestRoi(mean_landmarks, options.roi, "mean landmarks"));
  } catch (const Error& e) {
    result->mean_measures.message = e.what();
  }
  result->model.emplace(std::move(model));
  result->timings_s.Add("mean measures", SecondsSince(start));
}

// A subject's outcome for the run's report and tables, without the arrays only its own files need (the
// report tells a resampled subject by `ok`, one with distances to the mean by their statistics' count):
// about 1 kB instead of 170 kB for a 51 x 101 grid, which the leader reads back beside the fourth tasks.
SubjectOutcome Summary(const SubjectOutcome& full) {
  SubjectOutcome s = full;
  s.surface = TriangleMesh();
  TriangleMesh& grid = s.grid.mesh;
  grid.vertices.positions.resize(0, 3);
  grid.vertices.normals.resize(0, 3);
  grid.vertices.colors.resize(0, 3);
  grid.vertices.scalars.clear();
  grid.faces.resize(0, 3);
  s.grid.shape_vector.resize(0);
  s.to_mean.closest.resize(0, 3);
  s.to_mean.distances.resize(0);
  return s;
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

fs::path ModelFilesFolder(const fs::path& work) { return work / "model_files"; }

void RemoveSubjectResults(const fs::path& work) {
  std::error_code ec;
  for (const char* phase : {"surface", "registered", "grids", "model", "outputs", "summary", "files",
                            "model_files", "mean.rec", "picture_scale"}) {
    fs::remove_all(work / phase, ec);
    if (ec) ThrowFailure("cannot remove the subjects' results: " + ec.message(), (work / phase).string());
  }
  if (fs::is_empty(work, ec)) fs::remove(work, ec);
}

double RemoveSubjectResultsOnFarm(TaskRunner& runner, const fs::path& work,
                                  const std::vector<std::string>& names, bool remove) {
  std::string why;
  if (!runner.BroadcastOutcome(remove, &why) || work.empty()) return 0.0;
  const Clock::time_point start = Clock::now();
  const auto n = static_cast<std::int64_t>(names.size());
  std::vector<double> done(static_cast<std::size_t>(n));
  const std::int64_t per_block = BlockRows(n, 8);
  runner.ComputeBlocks(
      BlockOffsets(n, per_block, 1),
      [&](int b, double* out) {
        const std::int64_t first = b * per_block, end = std::min(n, first + per_block);
        for (std::int64_t i = first; i < end; ++i) {
          std::error_code ec;
          for (const char* phase : {"surface", "registered", "grids", "model", "outputs", "summary"}) {
            fs::remove(work / phase / (names[i] + ".rec"), ec);
          }
          fs::remove_all(SubjectFilesFolder(work, names[i]), ec);
          out[i - first] = 1.0;
        }
      },
      done.data());
  if (runner.IsLeader()) RemoveSubjectResults(work);  // what is left: the phases' folders, the mean
  return SecondsSince(start);
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

  // 7-9. The model of the subjects that made it, on every process, from their grids (with a work folder,
  // read back without their surfaces: they are not all held at once). Each subject's part of it (alignment,
  // fills) is committed for its third task (8: its distance to the mean, its files), which runs on the farm
  // while the leader decomposes the model's Gram matrix, and so does the fourth (9: its picture on the
  // colour scale of all of them). If the model stops short of that, they run after it.
  SubjectStore modelled(run.work, "model", inputs), finished(run.work, "outputs", inputs);
  SubjectStore summaries(run.work, "summary", inputs);
  std::exception_ptr model_error;    // the leader's: reported once the others are let go
  bool model_failed = false;         // every process's: the model threw (a collective's error reaches all)
  std::optional<TriangleMesh> mean;  // the mean shape, on every process (BuildModel)
  const std::vector<int> no_tasks;

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
    if (s.ok && mean) {
      const Clock::time_point start = Clock::now();
      s.to_mean = ComputeDistanceMap(s.grid.mesh.vertices.positions, *mean, options.distance, "mean shape");
      s.timings_s.Add("distance", SecondsSince(start));
    }
    if (run.subject_files) {
      const Clock::time_point start = Clock::now();
      const fs::path folder = SubjectFilesFolder(run.work, s.name);
      fs::create_directories(folder);
      run.subject_files(s, folder);
      s.timings_s.Add("files", SecondsSince(start));
    }
    if (in_memory) {
      result.subjects[i] = std::move(s);
    } else {
      s.surface = TriangleMesh();
      summaries.Put(i, Summary(s));  // for the leader's report, first: `finished` commits the task
      finished.Put(i, s);            // commits the subject's third task
    }
  };
  // 8-9 on every process (a collective): the third tasks; the colour scale, from blocks of subjects shared
  // among the processes; the fourth tasks, beside which the leader reads every subject's summary back.
  bool subjects_done = false;
  auto finish_subjects = [&] {
    runner.Run(model_error ? no_tasks : finished.Missing(largest_first), finish);
    std::future<double>
        read_back;  // its seconds; a failure is the leader's, thrown once the others are let go
    std::exception_ptr read_back_error;
    if (runner.IsLeader() && !in_memory && !model_error) {
      read_back = std::async(std::launch::async, [&] {
        const Clock::time_point start = Clock::now();
        try {
          for (int i = 0; i < n; ++i) result.subjects[i] = summaries.Get(i);
        } catch (...) {
          read_back_error = std::current_exception();
        }
        return SecondsSince(start);
      });
    }
    // 9. The files that need every subject's distances (the report's maps on one colour scale).
    if (run.subject_pictures) {
      double scale = 0.0;
      if (run.picture_scale && !model_failed) {  // after a failure the summaries may not all be there
        const std::int64_t per_block = BlockRows(n, 8);
        std::vector<double> scales(static_cast<std::size_t>((n + per_block - 1) / per_block));
        runner.ComputeBlocks(
            BlockOffsets(static_cast<std::int64_t>(scales.size()), 1, 1),
            [&](int b, double* out) {
              std::vector<SubjectOutcome> block;
              for (std::int64_t i = b * per_block; i < std::min<std::int64_t>(n, (b + 1) * per_block); ++i)
                block.push_back(in_memory ? result.subjects[i] : summaries.Get(static_cast<int>(i)));
              *out = run.picture_scale(block);
            },
            scales.data());
        scale = *std::max_element(scales.begin(), scales.end());
      }
      std::mutex seconds_mutex;
      double seconds = 0.0;  // this process's part
      runner.Run(model_error ? no_tasks : largest_first, [&](int i) {
        const Clock::time_point start = Clock::now();
        const SubjectOutcome s = in_memory ? result.subjects[i] : finished.Get(i);
        run.subject_pictures(s, scale, SubjectFilesFolder(run.work, s.name));
        const std::lock_guard<std::mutex> lock(seconds_mutex);
        seconds += SecondsSince(start);
      });
      result.timings_s.Add("pictures", seconds);
    }
    if (read_back.valid()) result.timings_s.Add("read back", read_back.get());
    if (read_back_error && !model_error) model_error = read_back_error;
    subjects_done = true;
  };
  {
    const Clock::time_point start = Clock::now();
    std::vector<std::string> names;
    for (const CohortSubject& s : inputs) names.push_back(s.name);
    std::function<SubjectOutcome(int)> light;
    std::function<void(int, SubjectOutcome)> keep;
    if (in_memory) {
      result.subjects.reserve(inputs.size());
      for (int i = 0; i < n; ++i) result.subjects.push_back(registered.Take(i));
      light = [&](int i) { return result.subjects[i]; };
      keep = [&](int i, SubjectOutcome s) { result.subjects[i] = std::move(s); };
    } else {
      std::error_code ec;
      if (runner.IsLeader()) fs::remove_all(run.work / "model", ec);  // before any process keeps a subject
      light = [&](int i) { return grids.Get(i); };
      keep = [&](int i, SubjectOutcome s) { modelled.Put(i, std::move(s)); };
      if (runner.IsLeader()) result.subjects.resize(inputs.size());
    }
    try {
      BuildModel(options, runner, names, light, keep, &mean, finish_subjects, &result);
    } catch (...) {
      model_failed = true;
      if (runner.IsLeader()) model_error = std::current_exception();  // the leader reports it, below
    }
    if (runner.IsLeader()) result.timings_s.Add("model", SecondsSince(start));
  }
  if (!subjects_done) finish_subjects();
  // 10. The files of the model alone (model.h5, its tables, the report's figures of it), one task each.
  if (run.model_files && !in_memory) {
    const Clock::time_point start = Clock::now();
    const std::vector<OutputFile> files = result.model ? run.model_files(result) : std::vector<OutputFile>();
    std::vector<int> order(files.size());
    std::iota(order.begin(), order.end(), 0);
    std::error_code ec;
    if (runner.IsLeader()) fs::remove_all(ModelFilesFolder(run.work), ec);  // a killed run's, before any task
    std::mutex seconds_mutex;
    double largest = 0.0;  // the longest task
    runner.Run(model_error || !result.model ? no_tasks : order, [&](int j) {
      const Clock::time_point begin = Clock::now();
      const fs::path to = ModelFilesFolder(run.work) / files[j].path;
      fs::create_directories(to.parent_path());
      files[j].write(to);
      const std::lock_guard<std::mutex> lock(seconds_mutex);
      largest = std::max(largest, SecondsSince(begin));
    });
    if (runner.IsLeader() && !files.empty()) {
      result.timings_s.Add("model outputs", SecondsSince(start));
      result.timings_s.Add("model outputs largest", largest);
    }
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
