// pectus datasets: the on-disk layout of synthetic data — one folder per subject with its sweeps, landmarks
// and a ground-truth folder, and a population folder for a cohort (docs/datasets.md, "Files").
#pragma once

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "datasets/chest_population.h"
#include "datasets/synth.h"
#include "shape/core/geometry.h"
#include "shape/core/landmarks.h"

namespace pectus::datasets {

/// Where to write a file meant for `target`: OutputTransaction::Stage for a command (all or nothing), or
/// the target itself (the default) for a library caller.
using StagePath = std::function<std::filesystem::path(const std::filesystem::path& target)>;

/// What a subject folder holds beyond the sweeps and the placed landmarks.
struct SubjectWriteOptions {
  double truth_spacing_mm = 1.5;  ///< edge length of the dense true meshes, mm, [0.2, 50]
  bool chest_wall = true;         ///< also write truth/chest_wall.ply
  bool sweep_truth = true;        ///< also write truth/sweep_NN.ply (per point: true hit, u, v, outlier)

  bool IsValid(std::string* why) const;
};

/// File names inside a subject folder (relative to it).
std::string SweepFileName(int sweep);       ///< "sweep_00.ply"
std::string SweepTruthFileName(int sweep);  ///< "truth/sweep_00.ply"
inline constexpr const char* kLandmarksFile = "landmarks.mrk.json";
inline constexpr const char* kTrueLandmarksFile = "truth/landmarks.mrk.json";
inline constexpr const char* kSurfaceFile = "truth/surface.ply";
inline constexpr const char* kChestWallFile = "truth/chest_wall.ply";
inline constexpr const char* kPosesFile = "truth/poses.json";
inline constexpr const char* kPosesConfFile = "truth/poses.conf";
inline constexpr const char* kSubjectFile = "truth/subject.json";

/// Writes one subject folder:
///   sweep_NN.ply             binary PLY, the points as the tracker placed them (scan frame, with the
///   tracker's
///                            error), scalars "line" and "column"
///   landmarks.mrk.json       the placed landmarks (3D Slicer markups, scan frame)
///   truth/surface.ply        dense skin mesh (scan frame), scalars "u", "v"
///   truth/chest_wall.ply     dense chest-wall mesh (optional)
///   truth/sweep_NN.ply       per point of sweep_NN.ply, in the same order: the noise-free hit (scan frame),
///                            scalars "u", "v", "outlier" (optional)
///   truth/poses.json         per sweep T_scan_sweep (true pose: scan = T_scan_sweep * sweep point), errors,
///                            breathing, strip; and the holes
///   truth/poses.conf         the same poses as a Stanford .conf (for `pectus merge --poses`)
///   truth/landmarks.mrk.json the exact landmarks
///   truth/subject.json       SubjectJson: parameters (exact shape), latent factors, seeds, extra
/// @return the number of bytes written
std::uintmax_t WriteSubjectFolder(const ScannedSubject& subject, const std::filesystem::path& folder,
                                  const SubjectWriteOptions& options = {}, const StagePath& stage = {});

/// Writes the population's truth into `folder`: population.json (PopulationJson), mean.ply (the exact mean
/// skin as a grid mesh on statistics.grid, scalars "u", "v"), mode_NN.ply (the mean's grid with the unit mode
/// vector as scalars "dx", "dy", "dz", and eigenvalue in the header comment) and mean_landmarks.mrk.json.
void WritePopulationFolder(const PopulationModel& population, const TrueShapeStatistics& statistics,
                           const std::filesystem::path& folder, const StagePath& stage = {});

/// A subject folder read back (sweeps, landmarks and every truth).
struct SubjectFolder {
  std::filesystem::path folder;
  SyntheticSubject subject;
  std::vector<PointCloud> sweeps;       ///< as the tracker placed them
  std::vector<Rigid3> T_scan_sweep;     ///< true pose per sweep
  std::vector<PointCloud> sweep_truth;  ///< empty if not written
  LandmarkSet landmarks;                ///< placed
  LandmarkSet true_landmarks;
};

/// Reads a folder written by WriteSubjectFolder; throws Error(kBadInput) naming the file at fault.
SubjectFolder ReadSubjectFolder(const std::filesystem::path& folder);

}  // namespace pectus::datasets
