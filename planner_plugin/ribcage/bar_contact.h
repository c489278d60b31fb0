// pectus planner: the bar as a shape (issue 14; the dissertation's aim, "location and shape of the bar").
// The surgeon bends the bar into a curve across the chest and lifts it; it touches the chest wall from
// behind wherever the sternum and the costal cartilages meet it, and only pushes. One-sided contact on the
// condensed compliance of the candidate nodes is a linear complementarity problem,
//   f >= 0,  w = g0 + C f >= 0,  f' w = 0,
// (f the contact forces along the push direction, g0 the gaps before loading, C the symmetric positive
// definite compliance of the candidates, K^-1 restricted to them), solved by projected Gauss-Seidel
// (Cottle, Pang & Stone 1992, §5.2; convergent for C positive definite).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "planner_plugin/ribcage/ribcage_fem.h"

namespace pectus::planner {

/// The bar as bent and placed: its anterior edge in the transverse plane of the bar level, y = Y(x) (the
/// patient's frame, LPS: x to the left, y posterior, mm), piecewise linear between stations and absent
/// beyond the first and last (the bar enters the chest there), then moved anteriorly (along the push
/// direction) by `lift_mm`. Contact is taken with small displacements: a node's gap is measured along
/// the push direction at its undeformed lateral position.
struct BarShape {
  double level_z_mm = 0.0;   ///< height of the bar's centre line (RibcageFem::BarLevelZ)
  std::vector<double> x_mm;  ///< lateral stations, ascending (at least two: the bar's ends)
  std::vector<double> y_mm;  ///< the anterior edge's y at each station
  double lift_mm = 0.0;      ///< how far the bar is pushed anteriorly from that curve

  /// A straight bar across the chest from x = -half_length to +half_length, its anterior edge at y mm.
  static BarShape Flat(double level_z_mm, double y, double half_length_mm);
  /// True where the bar is (between the first and last stations).
  bool Spans(double x) const { return x >= x_mm.front() && x <= x_mm.back(); }
  /// Y(x), mm (before the lift), for x the bar spans.
  double Y(double x) const;
  /// False, with the reason, if the stations are empty, of different lengths, not ascending or not finite.
  bool IsValid(std::string* why) const;
};

/// How the contact is solved.
struct BarContactOptions {
  /// The bar's width along the body (mm, > 0): nodes within half of it of the bar level are candidates.
  double width_mm = 12.0;
  /// Projected Gauss-Seidel stops when every complementarity residual min(f_i C_ii, w_i) is below this
  /// (mm, > 0).
  double tolerance_mm = 1e-6;
  int max_sweeps = 100000;  ///< at most this many sweeps over the candidates
  int block_columns = 64;   ///< right-hand sides solved together for the compliance

  /// False, with the reason, for a value out of range.
  bool IsValid(std::string* why) const;
};

/// The solved contact.
struct BarContactResult {
  /// Candidate nodes: boundary nodes of the sternum and the costal cartilages on faces that face
  /// posteriorly, within half the bar's width of its level and within its lateral span.
  std::vector<std::int32_t> nodes;
  std::vector<int> regions;  ///< per candidate: RibcageRegion (sternum or cartilage)
  Eigen::VectorXd gap0_mm;   ///< per candidate: gap to the bar before loading (< 0: the bar is inside)
  Eigen::VectorXd force_n;   ///< per candidate: contact force along the push direction, >= 0, N
  Eigen::VectorXd gap_mm;    ///< per candidate: gap after loading, from the compliance, >= 0 at the solution
  double total_force_n = 0.0;
  int contacts = 0;  ///< candidates with a force
  int sweeps = 0;
  bool converged = false;
  double residual_mm = 0.0;  ///< largest complementarity residual at the end
  Points3 displacement;      ///< every node, #nodes by 3 (mm): the direct FE solve with the forces found
  std::string message;       ///< one line: contacts (sternum, cartilage), total force, sweeps
};

/// Solves the contact of `bar` with the chest wall of `fem`'s ribcage. The compliance of the candidates
/// costs one right-hand side per candidate on the factorisation; the deformed ribcage is one more solve
/// with the contact forces. Throws Error(kUsage) for invalid options or bar, Error(kFailure) if no
/// candidate lies within the bar's width of its level (off the sternum).
BarContactResult SolveBarContact(const RibcageFem& fem, const BarShape& bar,
                                 const BarContactOptions& options = {});

}  // namespace pectus::planner
