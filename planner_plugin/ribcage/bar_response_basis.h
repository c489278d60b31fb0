// pectus planner: the chest's exact response to the bar at any position and force, at haptic rates
// (issue 14). The FE model is linear and the bar's push is a weighted sum of unit loads on the nodes of
// the sternum's back: a bar at level s with force F loads node j with F w_j(s) d (d the push direction,
// w_j(s) the consistent weights of its raised-cosine contact profile, summing to 1), so the displacement
// is u(s, F) = F P K^-1 D w(s) at the output points P (bone surface, skin through its fixed ties to the
// bone, landmarks: each a fixed linear combination of nodes). The basis solves the bar at finely sampled
// levels on the one factorisation (many right-hand sides at once), takes the truncated SVD of those
// responses as the modes U_r (to a stated tolerance), and the mixing M = U_r' P K^-1 D by the adjoint
// (r right-hand sides, not one per contact node): u(s, F) = F U_r M w(s). An evaluation is then one
// small product, w(s) entering through prefix sums over the same quadrature as RibcageFem::NodalForces,
// without allocation, lock or throw.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "planner_plugin/ribcage/ribcage_fem.h"
#include "shape/core/timings.h"

namespace pectus::planner {

/// An output point: a fixed linear combination of mesh nodes, (node, weight) pairs (a bone vertex is one
/// node with weight 1; a skin vertex its ties, SkinSurface::ties).
using NodeTies = std::vector<std::pair<std::int32_t, double>>;

/// How the basis is built.
struct BarResponseBasisOptions {
  /// The compression keeps the fewest singular vectors of the output response for which no coordinate
  /// of any evaluation up to `max_force_n` can differ from the uncompressed response by more than this,
  /// mm (the bound sigma_{r+1} max_force_n; BarResponseBasis::truncation_bound_mm_per_n). Default
  /// 0.003 mm at 2000 N: a third of what the planner is asked to hold against the direct solve (the
  /// differences measured are a hundredth of the bound: 1.1e-4 mm at most over patients 57 and 45 with
  /// 0.003; 0.001 kept 4-5 more modes, 15 % more time per update, for 7.5e-5 mm).
  double tolerance_mm = 3e-3;
  double max_force_n = 2000.0;  ///< the largest bar force the tolerance is stated for, N (> 0)
  /// Bar levels sampled per contact width for the modes (the responses to the bar there span what any
  /// bar does; > 0). 8: every 1.5 mm for the 12 mm bar.
  int samples_per_width = 8;
  /// Right-hand sides solved together (memory: 3 #nodes doubles each, twice). > 0.
  int block_columns = 64;

  /// False, with the reason, for a value out of range.
  bool IsValid(std::string* why) const;
};

/// Reusable buffers for evaluation (one per thread that evaluates): sized once by
/// BarResponseBasis::MakeWorkspace(), so that evaluation never allocates.
struct BarResponseWorkspace {
  Eigen::VectorXd weights;            ///< per contact node
  Eigen::VectorXd coefficients;       ///< per retained singular vector
  std::vector<std::int32_t> touched;  ///< contact nodes with a weight
  std::vector<std::uint8_t> mark;     ///< per contact node: 1 if in `touched`
};

/// The exact, compressed response of one patient's chest to the bar.
class BarResponseBasis {
 public:
  /// What a basis is made of, to store it (io/fem_dataset_h5: /patients/<id>/response_basis) and make it
  /// again without the finite element model: the modes, the mixing, the exact lift, the contact nodes and
  /// the quadrature of the sternum's back. What evaluation derives from them (panels, prefix sums) is
  /// recomputed on loading.
  struct Stored {
    Eigen::Index num_points = 0;     ///< output points (3 #points rows of `modes`)
    double contact_width_mm = 0.0;   ///< the bar's contact width (RibcageFemOptions)
    double notch_z_mm = 0.0;         ///< height of the sternal notch (bar positions are measured from it)
    double sternal_length_mm = 0.0;  ///< for bar positions given as fractions
    double truncation_bound_mm_per_n = 0.0;
    std::vector<std::int32_t> contact_nodes;  ///< #contact nodes: mesh nodes of the sternum's back
    Eigen::VectorXd quadrature_z;             ///< #quadrature points, ascending, mm
    Eigen::VectorXd quadrature_weight;        ///< #quadrature points, area weights, mm^2
    Eigen::MatrixXi quadrature_contact;       ///< #quadrature points by 6: indices into contact_nodes
    Eigen::MatrixXd quadrature_N;             ///< #quadrature points by 6: shape function values
    Eigen::MatrixXf modes;                    ///< 3 #points by rank: the orthonormal modes U_r
    Eigen::MatrixXd mixing;                   ///< rank by #contact nodes: M = U_r' P K^-1 D
    Eigen::VectorXd lift;                     ///< #contact nodes: sternal lift per newton at each, mm/N
    Eigen::VectorXd singular_values;          ///< of the sampled responses, descending, mm/N
  };
  /// The basis as stored.
  Stored ToStored() const;
  /// A basis from stored arrays. Throws Error(kBadInput) naming `source` for anything inconsistent (a
  /// shape that does not match, an index out of range, a non-finite or out-of-order value).
  BarResponseBasis(Stored stored, const std::string& source);

  /// Builds the basis of the response at `points` (each a combination of nodes; their displacements are
  /// the output) and of the sternal lift (RibcageFem::SternumLift) to the bar on the sternum's posterior
  /// faces. Throws Error(kUsage) for invalid options or a tie to a node outside the mesh.
  BarResponseBasis(const RibcageFem& fem, const std::vector<NodeTies>& points,
                   const BarResponseBasisOptions& options = {});

  /// A workspace for Evaluate(), LiftPerNewton() and Weights().
  BarResponseWorkspace MakeWorkspace() const;

  /// The contact weights w_j(level) of a bar at height `level_z_mm` into `ws->weights` (zero elsewhere);
  /// false if the profile there touches no contact face (the bar is off the sternum). No allocation.
  bool Weights(double level_z_mm, BarResponseWorkspace* ws) const noexcept;

  /// Displacements (#points by 3, row-major, mm) of the output points for a bar at `level_z_mm` pushing
  /// with `force_n` into `out` (3 #points doubles): the r coefficients from prefix sums over the contact
  /// profile's quadrature (two binary searches), then one product with the modes. False, with `out`
  /// untouched, if the bar is off the sternum. No allocation, lock or throw: callable from a 1 kHz thread.
  /// Only rows [first_row, end_row) of `out` are written if given (end_row < 0: to the last), the
  /// others untouched: the time is that share of the whole.
  bool Evaluate(double level_z_mm, double force_n, BarResponseWorkspace* ws, double* out,
                Eigen::Index first_row = 0, Eigen::Index end_row = -1) const noexcept;

  /// The r coefficients per newton of a bar at `level_z_mm` into `ws->coefficients`: the displacement
  /// under force F is F U_r c (CopyModes()). False, with the coefficients untouched, off the sternum. No
  /// allocation, lock or throw. For a host that evaluates the basis itself (the planner page).
  bool CoefficientsPerNewton(double level_z_mm, BarResponseWorkspace* ws) const noexcept;

  /// The modes U_r, 3 #points by rank, row after row (the rows of Evaluate()'s output), into `out`.
  void CopyModes(float* out) const noexcept;

  /// Sternal lift per newton of a bar at `level_z_mm` (mm/N), 0 if off the sternum; the force for a
  /// wanted lift is lift / this. O(log #quadrature points), no allocation.
  double LiftPerNewton(double level_z_mm) const noexcept;

  /// The bar level z of a position along the sternum (fraction of its length, or mm: as BarLoad).
  double LevelZ(const BarLoad& load) const {
    return notch_z_mm_ - (load.position_in_mm ? load.position : load.position * sternal_length_mm_);
  }

  Eigen::Index num_points() const { return num_points_; }
  Eigen::Index num_contact_nodes() const { return static_cast<Eigen::Index>(contact_nodes_.size()); }
  Eigen::Index rank() const { return rank_; }
  /// Bytes held by the basis (the compressed response, the quadrature and the lift row).
  std::size_t bytes() const;
  /// The compression's error at the sampled bar levels (every 16th of the contact width; 2-norm over every
  /// output coordinate), mm per newton of bar force. Between them it is measured (tests, benchmark).
  double truncation_bound_mm_per_n() const { return truncation_bound_mm_per_n_; }
  /// Wall time of the build, s: "solve_bar_levels" (the bar at the sampled levels), "compress" (SVD),
  /// "solve_adjoint" (the mixing and the lift, rank + 1 right-hand sides), "pack" (panels, prefix sums).
  const Timings& timings_s() const { return timings_s_; }
  /// Singular values of the responses to the bar at the sampled levels (descending), mm/N.
  const Eigen::VectorXd& singular_values() const { return singular_values_; }

 private:
  struct QuadraturePoint {
    double z = 0.0, weight = 0.0;
    std::int32_t contact[6] = {};  // indices into contact_nodes_
    double N[6] = {};
  };
  Eigen::Index num_points_ = 0;
  std::vector<std::int32_t> contact_nodes_;  // mesh nodes of the sternum's back
  std::vector<QuadraturePoint> quadrature_;  // sorted by z
  double contact_width_mm_ = 0.0, notch_z_mm_ = 0.0, sternal_length_mm_ = 0.0;
  // The quadrature window |z_q - level| < W: [first, last) into z_, and cos, sin of pi level / W.
  bool Window(double level_z_mm, Eigen::Index* first, Eigen::Index* last, double* c,
              double* s) const noexcept;
  // The window's sum of w_q phi_q x_q from the prefix sums of x_q, x_q cos(pi z_q / W), x_q sin(...).
  static double WindowSum(const Eigen::VectorXd (&prefix)[3], Eigen::Index first, Eigen::Index last, double c,
                          double s) noexcept;
  // Below this fraction of the whole back's area the profile counts as off the sternum.
  static constexpr double kLeastArea = 1e-9;
  // The modes U_r (3 #points by r, orthonormal columns) packed in panels of kPanel output coordinates:
  // panel p holds rows kPanel p .. kPanel p + kPanel - 1 (zero beyond the last) column after column, so
  // the update reads it once, contiguously, and sums kPanel coordinates side by side (vectorised, each
  // in order). Single precision (half the bytes; its rounding, 6e-8 of each term, is far below the
  // tolerance), summed in double.
  static constexpr int kPanel = 8;
  std::vector<float> panels_;
  // U_r(i, j) from the panels.
  float Mode(Eigen::Index i, Eigen::Index j) const noexcept {
    return panels_[static_cast<std::size_t>((i / kPanel) * kPanel * rank_ + j * kPanel + i % kPanel)];
  }
  Eigen::Index rows_ = 0, rank_ = 0;
  Eigen::VectorXd lift_;    // per contact node: sternal lift per newton (exact, uncompressed)
  Eigen::MatrixXd mixing_;  // rank by #contact nodes (kept to store the basis)
  // Packs the modes into panels_ and the prefix sums from quadrature_, mixing_ and lift_.
  template <typename Modes>
  void Pack(const Modes& modes);
  Eigen::VectorXd z_;  // the quadrature points' heights, ascending
  // Prefix sums over the quadrature points (index q + 1: points 0..q), plain, times cos, times sin.
  Eigen::VectorXd prefix_area_[3], prefix_lift_[3];
  Eigen::MatrixXd prefix_mixing_[3];  // r by #quadrature points + 1
  double truncation_bound_mm_per_n_ = 0.0;
  Eigen::VectorXd singular_values_;
  Timings timings_s_;
};

}  // namespace pectus::planner
