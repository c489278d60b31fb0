#include "shape/surface/merge_sweeps.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <optional>

#include "registration/voxel_downsample.h"
#include "shape/core/error.h"
#include "shape/core/log.h"
#include "shape/core/number_format.h"
#include "shape/core/timings.h"
#include "shape/surface/adjust_poses.h"
#include "shape/surface/adjust_poses_to_tracker.h"
#include "shape/surface/cloud_filter.h"
#include "shape/surface/sweep_graph.h"

namespace pectus {
namespace {

using Clock = std::chrono::steady_clock;

double AngleDeg(const Eigen::Matrix3d& R) {
  return std::acos(std::clamp((R.trace() - 1.0) / 2.0, -1.0, 1.0)) * 180.0 / M_PI;
}

// The prior's weights of a sweep's twist (rotation rad, translation mm) about its centre.
Eigen::Matrix<double, 6, 1> PriorWeights(const PosePrior& prior) {
  const double wr = 1.0 / std::pow(prior.rotation_sd_deg * M_PI / 180.0, 2);
  const double wt = 1.0 / std::pow(prior.translation_sd_mm, 2);
  Eigen::Matrix<double, 6, 1> w;
  w << wr, wr, wr, wt, wt, wt;
  return w;
}

// A twist about the origin as a twist about c (the motion of c is v + w x c).
Eigen::Matrix<double, 6, 6> TwistAboutPoint(const Eigen::Vector3d& c) {
  Eigen::Matrix<double, 6, 6> m = Eigen::Matrix<double, 6, 6>::Identity();
  m.block<3, 3>(3, 0) << 0, c.z(), -c.y(), -c.z(), 0, c.x(), c.y(), -c.x(), 0;
  return m;
}

// The expected sum over sweeps of the squared correction, in the prior's units, that the data's noise
// alone puts into the poses: sum_s trace(W C_ss), C = A^-1 H A^-1 with A the tracker step's joint normal
// matrix (twists about the origin), H = A less the priors' blocks (the data's information). 0 without A.
double CorrectionNoise(const Eigen::MatrixXd& A, const std::vector<Rigid3>& P,
                       const std::vector<SweepSurface>& sweeps, const PosePrior& prior) {
  const Eigen::Index m = A.rows();
  if (m == 0 || m != Eigen::Index(6 * P.size())) return 0.0;
  const Eigen::Matrix<double, 6, 1> w = PriorWeights(prior);
  Eigen::MatrixXd H = A;
  std::vector<Eigen::Matrix<double, 6, 6>> M(P.size());
  for (std::size_t s = 0; s < P.size(); ++s) {
    M[s] = TwistAboutPoint(P[s] * sweeps[s].centroid);
    H.block<6, 6>(Eigen::Index(6 * s), Eigen::Index(6 * s)) -= M[s].transpose() * w.asDiagonal() * M[s];
  }
  const Eigen::LDLT<Eigen::MatrixXd> ldlt(A);
  const Eigen::MatrixXd A_inv = ldlt.solve(Eigen::MatrixXd::Identity(m, m));
  const Eigen::MatrixXd C = A_inv * H * A_inv;
  double noise = 0.0;
  for (std::size_t s = 0; s < P.size(); ++s) {
    const Eigen::Matrix<double, 6, 6> Cs =
        M[s] * C.block<6, 6>(Eigen::Index(6 * s), Eigen::Index(6 * s)) * M[s].transpose();
    noise += (w.asDiagonal() * Cs).trace();
  }
  return std::isfinite(noise) ? std::max(0.0, noise) : 0.0;
}

}  // namespace

bool SweepMergeOptions::IsValid(std::string* why) const {
  auto fail = [&](const std::string& m) {
    if (why) *why = m;
    return false;
  };
  if (!(tracker_deg >= 0 && tracker_deg <= 30) || !(tracker_mm >= 0 && tracker_mm <= 100))
    return fail("tracker accuracy must be in [0, 30] degrees and [0, 100] mm");
  if (!(tracker_lever_mm >= 0 && tracker_lever_mm <= 1e4)) return fail("tracker lever must be in [0, 10 m]");
  if (!(overlap_distance_mm >= 0) || !std::isfinite(overlap_distance_mm))
    return fail("overlap distance must be >= 0 mm");
  if (min_overlap_fraction < 0 || min_overlap_fraction >= 1) return fail("minimum overlap must be in [0, 1)");
  if (global_rounds < 0 || global_points_per_pair < 10)
    return fail("global rounds >= 0 and points per pair >= 10");
  if (global_max_distance_mm < 0) return fail("global gate must be >= 0");
  if (smoothing_mm < 0) return fail("smoothing must be >= 0 mm");
  if (outlier_neighbours < 0 || outlier_std_ratio <= 0) return fail("outlier neighbours >= 0 and ratio > 0");
  if (target_spacing_mm < 0) return fail("target spacing must be >= 0 mm");
  if (!(final_min_pinned_ratio >= 1.0) || !std::isfinite(final_min_pinned_ratio))
    return fail("the final pinned ratio must be >= 1");
  return surface.IsValid(why) && pairwise.IsValid(why) && tracker_adjustment.IsValid(why);
}

bool SweepMergeOptions::HasTrackerPrior() const { return tracker_deg > 0 || tracker_mm > 0; }

double SweepMergeOptions::StartingRadiusMm() const {
  if (overlap_distance_mm > 0) return overlap_distance_mm;
  if (!HasTrackerPrior()) return 5.0;
  const double at_skin = std::hypot(tracker_mm, tracker_deg * M_PI / 180.0 * tracker_lever_mm);
  return 3.0 * std::sqrt(2.0) * at_skin;
}

SweepMergeResult MergeSweeps(const std::vector<PointCloud>& clouds, const std::vector<Rigid3>& start,
                             const SweepMergeOptions& options, const std::vector<std::string>& names) {
  std::string why;
  if (!options.IsValid(&why)) ThrowUsage("merge options: " + why);
  if (clouds.empty()) ThrowBadInput("sweeps", "no sweeps to merge");
  if (clouds.size() != start.size()) {
    ThrowBadInput("poses",
                  std::to_string(start.size()) + " poses for " + std::to_string(clouds.size()) + " sweeps");
  }
  if (!names.empty() && names.size() != clouds.size()) ThrowUsage("merge: one name per sweep, or none");
  if (!options.tracker_poses.empty() && options.tracker_poses.size() != clouds.size())
    ThrowUsage("merge: one tracker reading per sweep, or none");
  if (options.anchor >= clouds.size())
    ThrowUsage("anchor sweep " + std::to_string(options.anchor) + " does not exist");
  const std::size_t n = clouds.size();
  auto name = [&](std::size_t s) { return names.empty() ? "sweep " + std::to_string(s) : names[s]; };
  SweepMergeResult result;

  // 1. Normals, border points, targets and subsamples of every sweep, in its own frame.
  auto t0 = Clock::now();
  std::vector<SweepSurface> sweeps;
  for (std::size_t s = 0; s < n; ++s) {
    sweeps.push_back(PrepareSweep(clouds[s], options.surface, name(s)));
    result.points_in += clouds[s].size();
  }
  double spacing = 0;
  for (const auto& w : sweeps) spacing += w.spacing_mm / double(n);

  // A world frame centred on the data, so that far-from-origin scans keep their precision.
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  for (std::size_t s = 0; s < n; ++s) centre += start[s] * sweeps[s].centroid / double(n);
  Rigid3 T_centred_world = Rigid3::Identity();
  T_centred_world.translation() = -centre;
  std::vector<Rigid3> P_start(n), P(n);
  for (std::size_t s = 0; s < n; ++s) P[s] = P_start[s] = T_centred_world * start[s];
  const double radius = options.StartingRadiusMm();
  OrientSweeps(P, radius, options.anchor, &sweeps);
  result.timings_s.Add("normals", SecondsSince(t0));

  // 2. Which sweeps overlap, on their surfaces within the starting radius (the tracker's error).
  t0 = Clock::now();
  // A sweep the tracker slid off its neighbour still shares with it what it shares at the truth: at the
  // starting poses, a sample within the radius of the other's edge counts. The data cannot tell a sweep
  // slid off a narrow overlap along a direction they hardly pin from one that only touches its neighbour;
  // both are linked, and the joint adjustment uses only the correspondences they really have (a sweep
  // that only touches keeps its tracker pose). A sweep with nothing within the radius is refused.
  std::vector<SweepLink> links = FindSweepLinks(sweeps, P, radius, options.min_overlap_fraction, radius);
  result.timings_s.Add("overlap", SecondsSince(t0));
  if (n > 1) {
    for (std::size_t s = 0; s < n; ++s) {
      if (std::any_of(links.begin(), links.end(), [&](const SweepLink& l) { return l.i == s || l.j == s; }))
        continue;
      std::size_t nearest = s;
      const double d = DistanceToNearestSweep(sweeps, P, s, &nearest);
      ThrowFailure(name(s) + " overlaps no other sweep: it shares less than " +
                   FormatSignificant(100.0 * options.min_overlap_fraction) +
                   " % of its area with any within " + FormatMm(radius) +
                   " at the starting poses, and the nearest, " + name(nearest) + ", is " + FormatMm(d) +
                   " away; give better starting poses or a larger --tracker-mm/--tracker-deg");
    }
  }
  const double gate = options.global_max_distance_mm > 0 ? options.global_max_distance_mm : 3.0 * spacing;
  std::vector<std::vector<SweepCorrespondence>> before(links.size());
  for (std::size_t k = 0; k < links.size(); ++k) {
    before[k] = FindSweepCorrespondences(sweeps, P, links[k].i, links[k].j, options.global_points_per_pair,
                                         std::max(radius, gate));
  }

  std::vector<bool> pairwise_ok(links.size(), false);
  std::vector<PairConstraintReport> pinned;  // with a prior: what each pair pinned in the last round
  if (options.refine_poses && n > 1) {
    std::optional<PosePrior> prior;
    if (options.HasTrackerPrior()) {
      // The tracker's error at a sweep's centroid: its translation and its rotation about the far origin.
      prior.emplace();
      prior->T_world_sweep = P_start;
      if (!options.tracker_poses.empty()) {
        for (std::size_t s = 0; s < n; ++s)
          prior->T_world_sweep[s] = T_centred_world * options.tracker_poses[s];
      }
      for (const auto& w : sweeps) prior->centre.push_back(w.centroid);
      prior->rotation_sd_deg = std::max(options.tracker_deg, 1e-3);
      prior->translation_sd_mm = std::max(
          std::hypot(options.tracker_mm, options.tracker_deg * M_PI / 180.0 * options.tracker_lever_mm),
          1e-3);
    } else {
      // 3. Without a prior: pairwise ICP on every linked pair (sweep j onto sweep i), poses from a tree.
      t0 = Clock::now();
      std::vector<Rigid3> relative(links.size());
      Progress progress("pairwise alignment", std::int64_t(links.size()));
      for (std::size_t k = 0; k < links.size(); ++k) {
        const auto [i, j, overlap] = links[k];
        const IcpResult r = AlignIcp(*sweeps[i].target, clouds[j].positions, sweeps[j].normals,
                                     P[i].inverse() * P[j], options.pairwise);
        relative[k] = r.T_target_source;
        pairwise_ok[k] = r.success;
        progress.Advance();
      }
      PosesFromTree(links, relative, pairwise_ok, options.anchor, &P);
      result.timings_s.Add("pairwise_icp", SecondsSince(t0));
    }

    // 4. Joint point-to-plane adjustment of all poses, with fresh correspondences every round, the gate
    // halving from the starting radius (with a prior) down to the finest gate.
    t0 = Clock::now();
    const bool final_rounds =
        prior && options.final_min_pinned_ratio < options.tracker_adjustment.min_pinned_ratio;
    Progress progress("global adjustment",
                      options.global_rounds *
                          (1 + (prior && options.fit_tracker_accuracy ? 3 : 0) + (final_rounds ? 1 : 0)));
    PoseAdjustmentOptions ao;
    ao.anchor = options.anchor;
    // Rounds from `first_gate`; with `fixed` the correspondences are found once and kept (the poses move by
    // less than the noise then, and the search is most of a round's cost).
    std::vector<SweepCorrespondence> pairs;
    TrackerAdjustmentOptions adjustment = options.tracker_adjustment;
    Eigen::MatrixXd information;  // the last tracker step's joint normal matrix
    // With `every_point`, each overlap's points are listed once at the first round (within twice the gate)
    // and all of them are paired every round.
    auto run_rounds = [&](double first_gate, int rounds, bool fixed, bool every_point = false) {
      double round_gate = first_gate;
      std::vector<std::vector<std::uint32_t>> rows;
      if (every_point) rows = OverlapRows(sweeps, P, links, 2.0 * first_gate);
      for (int round = 0; round < rounds; ++round) {
        if ((!fixed || round == 0) && every_point)
          pairs = AllCorrespondences(sweeps, P, links, rows, round_gate);
        else if (!fixed || round == 0)
          pairs = AllCorrespondences(sweeps, P, links, options.global_points_per_pair, round_gate);
        const std::vector<Rigid3> previous = P;
        if (prior) {
          const TrackerAdjustmentResult a = AdjustPosesToTracker(pairs, sweeps, *prior, &P, adjustment);
          result.global_rms_before_mm = a.rms_before_mm;
          result.global_rms_after_mm = PointToPlaneRms(pairs, P);
          pinned = a.pairs;
          information = a.information;
        } else {
          const PoseAdjustmentResult a = AdjustPoses(pairs, &P, ao);
          result.global_rms_before_mm = a.rms_before_mm;
          result.global_rms_after_mm = a.rms_after_mm;
        }
        ++result.global_rounds;
        progress.Advance();
        double change_mm = 0;  // largest movement of a sweep's sample, roughly
        for (std::size_t s = 0; s < n; ++s) {
          const Rigid3 d = P[s] * previous[s].inverse();
          const Eigen::Vector3d c = P[s] * sweeps[s].centroid;
          const double extent = (ComputeBounds(clouds[s].positions).extent().norm()) / 2.0;
          change_mm = std::max(change_mm, (d * c - c).norm() + AngleDeg(d.linear()) * M_PI / 180.0 * extent);
        }
        if (round_gate <= gate && change_mm < 0.01 * spacing) break;
        round_gate = std::max(gate, round_gate / 2.0);
      }
    };
    run_rounds(prior ? std::max(radius, gate) : gate, options.global_rounds, false);
    // The tracker's actual accuracy, from the directions the overlaps pin (empirical Bayes): each pinned
    // direction of a pair's relative pose carries about one unit of the prior's variance, so the sweeps'
    // squared corrections in the prior's units, summed and divided by the number of pinned directions,
    // estimate the square of the factor by which the stated accuracy is off. The prior then holds what
    // the overlaps leave free with the accuracy the tracker showed, and the poses are adjusted again from
    // where they are: up to six times, while the factor is off 1 by more than 25 % and not clamped (an
    // exact tracker takes four to six fits down to the floor, each about halving it).
    const double stated_deg = prior ? prior->rotation_sd_deg : 0.0;
    const double stated_mm = prior ? prior->translation_sd_mm : 0.0;
    double total = 1.0;
    for (int fit = 0; prior && options.fit_tracker_accuracy && fit < 6; ++fit) {
      double sum = 0.0;
      for (std::size_t s = 0; s < n; ++s) {
        const Rigid3& read = prior->T_world_sweep[s];
        const Eigen::AngleAxisd turned(P[s].linear() * read.linear().transpose());
        const Eigen::Vector3d moved = P[s] * sweeps[s].centroid - read * sweeps[s].centroid;
        sum += std::pow(turned.angle() * 180.0 / M_PI / prior->rotation_sd_deg, 2) +
               moved.squaredNorm() / std::pow(prior->translation_sd_mm, 2);
      }
      int directions = 0;
      for (const auto& pc : pinned) directions += pc.pinned_directions;
      // The corrections hold the data's own noise as well as the tracker's error: take off its expected
      // share, sum_s trace(W C_ss), C = A^-1 H A^-1 the covariance the noise gives the poses (A the last
      // step's joint normal matrix, H its data part, W the prior's weights), so that exact poses read as
      // an exact tracker and not as one off by the data's noise (an unbiased moment estimate).
      const double noise = CorrectionNoise(information, P, sweeps, *prior);
      const double factor = std::sqrt(std::max(0.0, sum - noise) / std::max(1, directions));
      if (factor > 0.8 && factor < 1.25) break;
      const double next = std::clamp(total * factor, 0.01, 3.0);
      if (next == total) break;
      total = next;
      prior->rotation_sd_deg = stated_deg * total;
      prior->translation_sd_mm = stated_mm * total;
      result.tracker_accuracy_factor = total;
      run_rounds(gate, options.global_rounds, true);
    }
    // Last, every direction the overlaps pin at all (final_min_pinned_ratio), from where the poses are,
    // held by the prior at the accuracy the tracker showed: a tracker error of millimetres is corrected
    // along the weakly pinned directions too, while the weak directions of a tracker found better than
    // the data pin them stay held.
    if (final_rounds) {
      adjustment.min_pinned_ratio = options.final_min_pinned_ratio;
      run_rounds(gate, options.global_rounds, false, options.final_every_point);
    }
    result.timings_s.Add("global_adjustment", SecondsSince(t0));
  }

  // Back to the caller's world frame; corrections and overlap residuals.
  const Rigid3 T_world_centred = T_centred_world.inverse();
  for (std::size_t s = 0; s < n; ++s) {
    result.T_world_sweep.push_back(T_world_centred * P[s]);
    const Rigid3 correction = result.T_world_sweep[s] * start[s].inverse();
    result.correction_deg.push_back(AngleDeg(correction.linear()));
    const Eigen::Vector3d c = start[s] * sweeps[s].centroid;
    result.correction_mm.push_back((correction * c - c).norm());
  }
  // The overlap of every link at the final poses, within the finest gate.
  const std::vector<SweepLink> final_links = FindSweepLinks(sweeps, P, gate, 0.0);
  for (std::size_t k = 0; k < links.size(); ++k) {
    for (const auto& l : final_links)
      if (l.i == links[k].i && l.j == links[k].j) links[k].overlap = l.overlap;
  }
  for (std::size_t k = 0; k < links.size(); ++k) {
    // Pairs that lay within the tracker's error of each other at the start but share nothing aligned (two
    // strips that only touch) are not reported.
    if (!(links[k].overlap > 0.0)) continue;
    SweepPairReport pr;
    pr.i = links[k].i;
    pr.j = links[k].j;
    pr.overlap_fraction = links[k].overlap;
    pr.pairwise_success = pairwise_ok[k];
    for (const auto& pc : pinned)
      if (pc.i == pr.i && pc.j == pr.j) pr.pinned_directions = pc.pinned_directions;
    pr.rms_before_mm = PointToPlaneRms(before[k], P_start);
    const auto after = FindSweepCorrespondences(sweeps, P, pr.i, pr.j, options.global_points_per_pair, gate);
    pr.rms_after_mm = PointToPlaneRms(after, P);
    std::vector<double> d;
    for (const auto& c : after) d.push_back((P[c.j] * c.p - P[c.i] * c.q).norm());
    if (!d.empty()) {
      std::nth_element(d.begin(), d.begin() + std::ptrdiff_t(d.size() / 2), d.end());
      pr.median_after_mm = d[d.size() / 2];
    }
    result.pairs.push_back(pr);
  }

  // 5. One cloud (centred frame): every sweep at its final pose, with its oriented normals.
  t0 = Clock::now();
  PointCloud merged;
  for (std::size_t s = 0; s < n; ++s) {
    PointCloud c;
    c.positions =
        (clouds[s].positions * P[s].linear().transpose()).rowwise() + P[s].translation().transpose();
    c.normals = sweeps[s].normals * P[s].linear().transpose();
    if (clouds[s].has_colors()) c.colors = clouds[s].colors;
    c.scalars["sweep"] = Eigen::VectorXd::Constant(c.size(), double(s));
    merged.Append(c);
  }
  BlendAlongNormals(options.smoothing_mm, &merged);
  result.timings_s.Add("blend", SecondsSince(t0));

  // 6. Statistical outlier removal, then decimation to the target spacing.
  t0 = Clock::now();
  std::vector<std::uint32_t> keep =
      StatisticalInliers(merged.positions, options.outlier_neighbours, options.outlier_std_ratio);
  result.outliers_removed = merged.size() - std::int64_t(keep.size());
  if (options.target_spacing_mm > 0)
    keep = VoxelDownsample(merged.positions, options.target_spacing_mm, &keep);
  result.merged = SelectRows(merged, keep);
  result.merged.positions.rowwise() += T_world_centred.translation().transpose();
  result.points_out = result.merged.size();
  result.timings_s.Add("filter", SecondsSince(t0));

  double worst_after = 0;
  for (const auto& pr : result.pairs) worst_after = std::max(worst_after, pr.rms_after_mm);
  char text[256];
  std::snprintf(text, sizeof text,
                "%zu sweeps, %zu overlapping pairs, worst pair RMS %.3f mm, %lld points out", n, links.size(),
                worst_after, static_cast<long long>(result.points_out));
  result.message = text;
  return result;
}

std::string SweepMergeResult::BriefReport() const {
  char text[160];
  std::snprintf(text, sizeof text, "; joint RMS %.3f -> %.3f mm; %.2f s", global_rms_before_mm,
                global_rms_after_mm, timings_s.Total());
  return message + text;
}

}  // namespace pectus
