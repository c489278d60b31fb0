// pectus: generalised Procrustes analysis (Gower 1975): a set of shapes given as corresponding points
// (grid vertices, or landmarks matched by label) brought rigidly or by similarities onto their mean.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "shape/core/geometry.h"
#include "shape/core/landmarks.h"

namespace pectus {

class TaskRunner;

/// Options of GeneralisedProcrustes.
struct ProcrustesOptions {
  bool estimate_scale = false;  ///< similarity transforms (the mean keeps the reference's size)
  /// The shape whose frame the mean is kept in: the mean starts as this shape and each new mean is placed
  /// back on it, so that the gauge does not drift. Absent: the mean starts as the plain average of the
  /// shapes and floats with them (the shape model's grids, whose frame is set by the registration).
  std::optional<int> reference = 0;
  /// Rounds of "align every shape to the mean, average"; every shape is then aligned once more, to the
  /// last mean, so that the shapes are aligned max_iterations + 1 times. 0: each shape aligned once to
  /// the starting mean.
  int max_iterations = 100;
  /// Stop when no mean point moves by more than this (mm). 0: run all max_iterations rounds.
  double tolerance_mm = 1e-6;
  double min_spread_ratio = 0.02;  ///< see LandmarkAlignmentOptions (0: no check of collinear points)

  /// False, with the reason in `why`, if a value is out of range.
  bool IsValid(std::string* why) const;
};

/// What GeneralisedProcrustes found.
struct ProcrustesResult {
  std::vector<Similarity3> T_mean_shape;  ///< per shape: its frame to the mean's frame
  Points3 mean_points;                    ///< #points by 3, the mean shape (mm), in the mean's frame
  int iterations = 0;                     ///< rounds run
  bool converged = false;                 ///< stopped on tolerance_mm
  double rms_mm = 0.0;                    ///< RMS distance of the aligned points to the mean (mm)
};

/// Generalised Procrustes analysis of corresponding point sets (Gower 1975; Dryden and Mardia 2016,
/// Alg. 7.1): align every shape to the current mean (Umeyama), average, place the new mean on the
/// reference shape (when there is one), repeat until the mean stops moving; finally align every shape to
/// the last mean. Throws Error(kUsage) for invalid options, Error(kBadInput) naming the shape at fault (via
/// `names`) for fewer than two shapes or shapes of different sizes, and Error(kFailure) naming it for
/// degenerate points.
/// The shapes' alignments run in blocks fixed by their number, shared among `runner`'s processes (MPI ranks:
/// a collective, every process calls it alike and gets the whole result) or this process's threads
/// (nullptr); each mean adds the blocks' sums in block order, so the result is the same bits on any number
/// of processes.
/// @param[in] shapes  two or more #points by 3 sets (mm), row k of each corresponding
/// @param[in] names   a name per shape for messages (file names), or empty
ProcrustesResult GeneralisedProcrustes(const std::vector<Points3>& shapes,
                                       const ProcrustesOptions& options = {},
                                       const std::vector<std::string>& names = {},
                                       TaskRunner* runner = nullptr);

/// What GeneralisedProcrustes of landmark sets found: the same, and the mean as landmarks.
struct LandmarkProcrustesResult : ProcrustesResult {
  LandmarkSet mean;  ///< mean landmarks (mm), in the mean's frame (the reference shape's by default)
  std::vector<std::string> skipped;  ///< labels not present in every shape (not used)
};

/// Generalised Procrustes analysis of labelled landmark sets: the point-set version on the labels present
/// in every set (at least 3, non-collinear), in the reference's order (the first set's without one).
/// Throws Error(kBadInput) naming the set at fault (via `names`) for fewer than two sets or too few
/// common labels.
/// @param[in] shapes  two or more landmark sets (mm)
/// @param[in] names   a name per set for messages (file names), or empty
LandmarkProcrustesResult GeneralisedProcrustes(const std::vector<LandmarkSet>& shapes,
                                               const ProcrustesOptions& options = {},
                                               const std::vector<std::string>& names = {});

}  // namespace pectus
