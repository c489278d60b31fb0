// pectus: bringing a whole cohort of scans into one frame: every scan to a chosen reference, or
// groupwise by generalised Procrustes analysis to the evolving mean (Gower 1975).
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "registration/generalised_procrustes.h"
#include "registration/register_pair.h"
#include "shape/core/geometry.h"
#include "shape/core/landmarks.h"
#include "shape/core/task_runner.h"

namespace pectus {

/// How a cohort is aligned.
enum class CohortMode {
  kToReference,  ///< every scan registered to the reference scan (landmarks, then ICP)
  kGroupwise,    ///< generalised Procrustes: every scan to the evolving mean surface
};

/// One scan of a cohort.
struct CohortScan {
  std::string name;                      ///< for messages and outputs (the file's stem)
  PointCloud cloud;                      ///< mm; normals estimated if absent
  std::optional<LandmarkSet> landmarks;  ///< all scans or none must have them
};

/// Options of AlignCohort.
struct CohortOptions {
  CohortMode mode = CohortMode::kToReference;
  int reference = 0;  ///< index of the reference scan (its frame is the cohort's frame)
  /// Landmark and ICP options of every registration. The defaults expect scans of different people,
  /// whose surfaces differ by millimetres and whose landmarks never coincide: a last ICP gate of 10 mm, a
  /// fit accepted up to 5 mm RMS, and instead of a limit on the landmarks' distance one on how far ICP
  /// moves them from the landmark fit (15 mm RMS).
  PairRegistrationOptions pair = [] {
    PairRegistrationOptions o;
    o.icp.final_max_distance_mm = 10.0;
    o.icp.max_rms_mm = 5.0;
    o.max_landmark_rms_mm = 0.0;  // off: two people's landmarks never coincide
    o.max_landmark_shift_mm = 15.0;
    return o;
  }();
  int max_groupwise_iterations = 20;     ///< kGroupwise: rounds of mean update and realignment
  double groupwise_tolerance_mm = 0.05;  ///< kGroupwise: stop when no scan moves more than this (mm, RMS)
  int mean_points = 20000;               ///< kGroupwise: points of the mean surface
  double mean_max_distance_mm = 5.0;     ///< kGroupwise: a scan contributes to a mean point within this (mm)

  /// False, with the reason in `why`, if a value is out of range.
  bool IsValid(std::string* why) const;
};

/// What AlignCohort found.
struct CohortResult {
  /// Per scan: its frame to the cohort frame (mm). The cohort frame is the reference scan's frame in both
  /// modes: the reference gets the identity.
  std::vector<Similarity3> T_frame_scan;
  std::vector<bool> success;            ///< per scan: the registration is good
  std::vector<std::string> messages;    ///< per scan: what was found or why it failed
  std::vector<double> rms_mm;           ///< per scan: RMS surface distance (to reference or mean)
  std::vector<double> inlier_fraction;  ///< per scan
  Points3 mean_points;                  ///< kGroupwise: the mean surface samples (cohort frame)
  std::optional<LandmarkProcrustesResult> procrustes;  ///< kGroupwise with landmarks: the landmark GPA
  int iterations = 0;                                  ///< kGroupwise: rounds run
  bool converged = true;                               ///< kGroupwise: stopped on the tolerance
  /// Wall time (s): "register" (to the reference), "procrustes" (landmarks), "groupwise".
  Timings timings_s;
  bool all_succeeded() const;
  /// One line for a log: "4 of 4 scans registered, 6 groupwise rounds, 3.2 s".
  std::string BriefReport() const;
};

/// Where AlignCohort's per-scan fits run and where they are kept (docs/cluster.md): the registrations to
/// the reference, and each groupwise round's ICP of the mean onto every scan, are tasks of `runner`; the
/// rest (the landmark Procrustes, each round's mean surface) is computed by every process alike.
struct CohortFarm {
  /// The task farm: null for this process's threads (SerialTaskRunner).
  TaskRunner* runner = nullptr;
  /// Each scan's fit is committed to `work/PHASE/NAME.fit` as it finishes (PHASE: to-reference,
  /// groupwise-R), bit for bit, and every process reads the others' fits from there: needed by a runner of
  /// several processes. Empty: the fits are kept in memory.
  std::filesystem::path work;
  /// Keep the fits already in `work` (a killed run, resumed with the same scans and options) and compute
  /// only the missing ones; false: the fits there are removed first.
  bool resume = false;
  /// Only this runner's fits, then return an empty result: one share of a job array (kToReference; the
  /// groupwise rounds need every scan's fit of the round before). Implies resume.
  bool fits_only = false;
  /// Every fit must be in `work` already (the shares' gather): Error(kUsage) naming the scans without one.
  bool gather = false;
};

/// Removes the fits AlignCohort kept in `work` (its phase folders), and `work` itself if that empties it.
void RemoveCohortFits(const std::filesystem::path& work);

/// Aligns a cohort (see CohortMode). The reference scan gets the identity (kToReference). A scan whose
/// fit is poor is marked success = false with the reason; nothing is dropped silently. Throws
/// Error(kUsage) for invalid options or an inconsistent cohort (some scans with landmarks, some without).
/// On a farm (`farm`), every process gets the same result, whatever the number of processes or threads.
CohortResult AlignCohort(const std::vector<CohortScan>& scans, const CohortOptions& options = {},
                         const CohortFarm& farm = {});

}  // namespace pectus
