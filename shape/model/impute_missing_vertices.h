// pectus: the vertices a subject's scan did not see, filled from the other subjects (statistical
// imputation). A grid vertex far from any scan data (an occlusion, an arm over the chest wall, a hole at
// the ROI's edge) carries only the resampler's continuation of its neighbours, which can be millimetres off
// where a hole reaches the grid's border; averaged into the mean and the modes, one such subject moves them.
// Here each subject's unseen vertices take their conditional expectation given its seen ones under the
// Gaussian shape model of the *other* subjects (leave the subject out: with it in, its own fill is in the
// span and would reproduce itself), iterated until the fills agree (an EM for the mean and covariance with
// missing data, Little & Rubin 2002, ch. 11; the PPCA posterior of a partial shape, Albrecht, Luthi et al.
// 2013, "Posterior shape models", Eq. 5); then a local Gaussian-process correction joins each fill to the
// seen vertices about it (ImputationOptions::local_scale_mm).
//
// The model of the others: mean mu and covariance C = Xc' Xc / (N' - 1) of their centred shape vectors Xc
// (N' = N - 1 rows), plus isotropic noise s^2. The fill of the unseen coordinates M given the seen ones O:
//   x_M = mu_M + C_MO (C_OO + s^2 I)^-1 (x_O - mu_O)
//       = mu_M + Xc_M' (Xc_O Xc_O' + (N' - 1) s^2 I)^-1 Xc_O (x_O - mu_O)       (Woodbury),
// an N' x N' system per subject, with Xc_O Xc_O' = Xc Xc' - Xc_M Xc_M' from the Gram matrix of all
// coordinates: O(N^2 3m) per sweep over the cohort, O(N^3 + N 3|M|) per subject.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

namespace pectus {

/// How unseen vertices are filled.
struct ImputationOptions {
  /// Sweeps over the cohort at most (each fills every subject from the others' current fills). >= 1.
  int max_iterations = 30;
  /// Stop when no filled coordinate moved by more than this in a sweep, mm (> 0).
  double tolerance_mm = 1e-3;
  /// Isotropic noise s of the shape model, mm (> 0): the part of a subject the others' span should not
  /// explain (resampling and scan noise). It damps the modes the seen vertices pin poorly; the fill is
  /// insensitive to it between 0.05 and 1 mm on the virtual scanner's cohorts (docs/benchmarks/model.md).
  double noise_mm = 0.2;
  /// Length scale (mm) of the local correction: the fill from the others predicts a hole from the whole
  /// shape and can step at the hole's rim; the difference between the subject's seen vertices and that
  /// prediction near the rim is carried into the hole by Gaussian-process regression with a squared
  /// exponential kernel of this length (regression kriging: the population model as the trend, a local
  /// Gaussian process for what it misses, as the augmented models of Luthi et al. 2018 add a smooth
  /// kernel to the PCA covariance). It fades to the population's prediction a few lengths inside. 0: off.
  double local_scale_mm = 10.0;
  /// Standard deviation of that local correction (mm, > 0): with noise_mm it sets how closely the
  /// correction follows the residuals at the rim.
  double local_sd_mm = 1.0;
  /// A subject is filled only if at least this fraction of its vertices is seen ((0, 1]); a subject
  /// seen less keeps the resampler's fill and is reported (ImputationResult::too_little_seen).
  double min_seen_fraction = 0.5;
  /// The model of the others is made of at most this many subjects (>= 2): the first max_others + 1 rows
  /// of the cohort (the core) but the one filled. Up to max_others + 1 subjects that is every other
  /// subject; in a larger cohort (thousands: docs/cluster.md) only the core's fills are iterated, and each
  /// subject beyond it is filled once from the converged core: O(K^3) per subject and O(K^2 3m) per sweep
  /// with K = max_others, rather than O(N^3) and O(N^2 3m), for a covariance estimated from K shapes.
  int max_others = 256;

  /// False, with the reason, for a value out of range.
  bool IsValid(std::string* why) const;
};

/// What the imputation did.
struct ImputationResult {
  Eigen::MatrixXd shapes;                 ///< N by 3m, the input with every unseen vertex filled, mm
  int iterations = 0;                     ///< sweeps over the cohort (its core: max_others) run
  bool converged = false;                 ///< the last sweep moved no fill by more than the tolerance
  double last_change_mm = 0.0;            ///< largest move of a filled coordinate in the last sweep
  std::vector<int> filled_vertices;       ///< per subject: vertices filled from the others
  std::vector<double> largest_change_mm;  ///< per subject: largest distance fill - input, mm
  std::vector<int> too_little_seen;       ///< subjects (rows) left as they were: too little seen
  std::string message;                    ///< one line: subjects and vertices filled, iterations
};

class TaskRunner;

/// Fills the unseen vertices of every subject from the others.
/// @param[in] shapes  N by 3m shape vectors (x1, y1, z1, x2, ...), mm, in one frame; N >= 3. The unseen
///                    entries are the starting values of the fill (e.g. the resampler's).
/// @param[in] seen    N by m: true where the vertex was seen (its value is data), false where it is filled
/// Throws Error(kBadInput) naming `what` for mismatched sizes, fewer than 3 subjects or a non-finite value,
/// Error(kUsage) for invalid options. Subjects with every vertex seen are returned unchanged.
/// With a `runner` of several processes (MPI ranks: docs/cluster.md) it is a collective: every process
/// calls it with the same shapes and options, each fills its share of the subjects at each step, and every
/// process returns the same result, the bytes of a run on one process.
ImputationResult ImputeMissingVertices(const Eigen::MatrixXd& shapes,
                                       const Eigen::Matrix<bool, Eigen::Dynamic, Eigen::Dynamic>& seen,
                                       const ImputationOptions& options = {},
                                       const std::string& what = "shapes", TaskRunner* runner = nullptr);

}  // namespace pectus
