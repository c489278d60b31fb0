// pectus: robust, gated, coarse-to-fine point-to-plane and symmetric ICP (registration/icp.h). The
// method and its equations: docs/registration.md.
#include "registration/icp.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <optional>
#include <sstream>

#include "registration/internal/icp_steps.h"
#include "registration/internal/radius_grid.h"
#include "registration/random_sample.h"
#include "registration/voxel_downsample.h"
#include "shape/core/error.h"
#include "shape/core/timings.h"

namespace pectus {
namespace {

using namespace icp_detail;  // NOLINT: the steps of one iteration, internal to this library

std::string Format(double value, int precision = 3) {
  std::ostringstream s;
  s.precision(precision);
  s << value;
  return s.str();
}

double RotationAngleDeg(const Eigen::Matrix3d& R) { return Eigen::AngleAxisd(R).angle() * kDegPerRad; }

// Source rows within the patches (all rows when there are none).
std::vector<std::uint32_t> PatchRows(const Points3& source, const IcpOptions& o) {
  std::vector<std::uint32_t> rows;
  rows.reserve(static_cast<std::size_t>(source.rows()));
  const double r2 = o.patch_radius_mm * o.patch_radius_mm;
  for (Eigen::Index i = 0; i < source.rows(); ++i) {
    bool inside = o.patch_centres.empty();
    for (const Eigen::Vector3d& c : o.patch_centres) {
      if ((source.row(i).transpose() - c).squaredNorm() <= r2) {
        inside = true;
        break;
      }
    }
    if (inside) rows.push_back(static_cast<std::uint32_t>(i));
  }
  return rows;
}

// Sorts distinct rows (each below `row_count`) into ascending order. A large run is sorted by marking its
// rows and collecting them in one pass over all rows, O(row_count), instead of O(k log k): the last level's
// growth sorts tens of thousands of rows. The result is the same either way.
void SortDistinctRows(std::vector<std::uint32_t>::iterator first, std::vector<std::uint32_t>::iterator last,
                      std::size_t row_count) {
  const auto k = static_cast<std::size_t>(last - first);
  if (k < 2) return;
  if (static_cast<double>(k) * std::log2(static_cast<double>(k)) < static_cast<double>(row_count)) {
    std::sort(first, last);
    return;
  }
  std::vector<std::uint8_t> marked(row_count, 0);
  for (auto it = first; it != last; ++it) marked[*it] = 1;
  auto out = first;
  for (std::size_t row = 0; row < row_count && out != last; ++row) {
    if (marked[row] != 0) *out++ = static_cast<std::uint32_t>(row);
  }
}

// The source sample of every level, finest last. Random levels are prefixes of one shuffle (nested);
// voxel levels subsample the next finer level's sample. With `rest`, the rows of the shuffle beyond the
// largest random sample, in random order: the last level grows from them.
std::vector<std::vector<std::uint32_t>> LevelSamples(const Points3& source,
                                                     const std::vector<std::uint32_t>& rows,
                                                     const std::vector<IcpLevel>& levels,
                                                     std::vector<std::uint32_t>* rest) {
  std::size_t most = 0;
  for (const IcpLevel& l : levels) most = std::max(most, static_cast<std::size_t>(l.points));
  // RandomSample's first k rows do not depend on how many it draws: the coarse levels are the same
  // with or without the rest.
  std::vector<std::uint32_t> shuffled =
      most > 0 ? RandomSample(rows, rest != nullptr ? rows.size() : most) : std::vector<std::uint32_t>();
  const std::size_t used = std::min(shuffled.size(), most);
  // Each level's new points in row order: scans store neighbours near each other, so successive queries
  // walk the same branches of the tree (fewer cache misses); the samples stay nested.
  std::vector<std::size_t> ends = {0, used};
  for (const IcpLevel& l : levels) ends.push_back(std::min(used, static_cast<std::size_t>(l.points)));
  std::sort(ends.begin(), ends.end());
  for (std::size_t k = 1; k < ends.size(); ++k) {
    SortDistinctRows(shuffled.begin() + static_cast<std::ptrdiff_t>(ends[k - 1]),
                     shuffled.begin() + static_cast<std::ptrdiff_t>(ends[k]),
                     static_cast<std::size_t>(source.rows()));
  }
  std::vector<std::vector<std::uint32_t>> samples(levels.size());
  for (std::size_t l = levels.size(); l-- > 0;) {
    const std::vector<std::uint32_t>& finer = l + 1 < levels.size() ? samples[l + 1] : rows;
    if (levels[l].points > 0) {
      const std::size_t count = std::min(used, static_cast<std::size_t>(levels[l].points));
      samples[l].assign(shuffled.begin(), shuffled.begin() + static_cast<std::ptrdiff_t>(count));
    } else if (levels[l].voxel_size_mm > 0.0) {
      samples[l] = VoxelDownsample(source, levels[l].voxel_size_mm, &finer);
    } else {
      samples[l] = finer;
    }
  }
  if (rest != nullptr) rest->assign(shuffled.begin() + static_cast<std::ptrdiff_t>(used), shuffled.end());
  return samples;
}

// How many of the N source points the last level's sample should grow to from n, where the pose's sd is
// `sd` (mm) and sampling may add at most `allowed` (mm): sd scales as 1/sqrt(n), and what sampling adds
// to the error of every point's estimate is sd_m sqrt(1 - m/N), so m >= 1 / (allowed^2 / (sd^2 n) + 1/N)
// (docs/registration.md). A quarter more than that, at least half as many again as now; every point
// once three quarters are due (they cost little more).
std::size_t GrownSampleSize(double sd, double allowed, std::size_t n, std::size_t N) {
  const double nd = static_cast<double>(n), Nd = static_cast<double>(N);
  const double need = 1.0 / (allowed * allowed / (sd * sd * nd) + 1.0 / Nd);
  const double next = std::max(1.25 * need, 1.5 * nd);
  return next >= 0.75 * Nd ? N : static_cast<std::size_t>(std::ceil(next));
}

// Inliers (the pairs found within the gate) and their RMS point-to-plane distance, out of `sample_size`.
void Summarise(const Pairs* pairs, std::size_t sample_size, IcpResult* result) {
  double r2 = 0.0;
  result->inliers = 0;
  for (std::size_t k = 0; k < pairs->r.size(); ++k) {
    if (pairs->target[k] == kNoMatch) continue;
    ++result->inliers;
    r2 += pairs->r[k] * pairs->r[k];
  }
  result->inlier_fraction =
      sample_size == 0 ? 0.0 : static_cast<double>(result->inliers) / static_cast<double>(sample_size);
  result->rms_mm = result->inliers > 0 ? std::sqrt(r2 / static_cast<double>(result->inliers)) : 0.0;
}

// The acceptance tests of the options: an empty list means a good fit.
std::vector<std::string> Problems(const IcpResult& r, const IcpOptions& o, int last_iterations,
                                  double reach) {
  std::vector<std::string> problems;
  if (!r.converged) {
    problems.push_back("did not converge in " + std::to_string(last_iterations) +
                       " iterations at the last level");
  }
  if (r.rms_mm > o.max_rms_mm) {
    problems.push_back("RMS distance " + Format(r.rms_mm) + " mm exceeds " + Format(o.max_rms_mm) + " mm");
  }
  if (r.inlier_fraction < o.min_inlier_fraction) {
    problems.push_back("only " + Format(100.0 * r.inlier_fraction) + " % of the source lies within " +
                       Format(reach) + " mm of the target (need " + Format(100.0 * o.min_inlier_fraction) +
                       " %)");
  }
  if (r.conditioning < o.min_conditioning) {
    problems.push_back("the overlap leaves a sliding direction (conditioning " + Format(r.conditioning) +
                       " < " + Format(o.min_conditioning) + ")");
  }
  return problems;
}

}  // namespace

IcpResult AlignIcp(const IcpTarget& target, const Points3& source_positions, const Points3& source_normals,
                   const Rigid3& T_target_source_initial, const IcpOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  std::string why;
  if (!options.IsValid(&why)) ThrowUsage("ICP: " + why);
  if (source_normals.rows() != 0 && source_normals.rows() != source_positions.rows()) {
    ThrowBadInput("ICP source", "has " + std::to_string(source_positions.rows()) + " points but " +
                                    std::to_string(source_normals.rows()) + " normals");
  }
  if (options.method == IcpMethod::kSymmetric && source_normals.rows() == 0) {
    ThrowBadInput("ICP source", "symmetric ICP needs source normals");
  }
  if (!source_positions.allFinite() || !source_normals.allFinite()) {
    ThrowBadInput("ICP source", "a position or normal is not finite");
  }
  if (!T_target_source_initial.matrix().allFinite()) ThrowBadInput("ICP", "the initial pose is not finite");

  IcpResult result;
  result.T_target_source = T_target_source_initial;
  auto finish = [&](const std::string& message) {
    result.message = message;
    result.timings_s.Add("icp", SecondsSince(start));
    return result;
  };

  // Work in the target's centred frame with a centred source: x_c = T_c (x - source_origin), where
  // T_c = T(-target_origin) T T(source_origin). Far-away frames cancel before any product is formed.
  const std::vector<std::uint32_t> considered = PatchRows(source_positions, options);
  if (considered.size() < static_cast<std::size_t>(options.min_correspondences)) {
    return finish("only " + std::to_string(considered.size()) + " source points" +
                  (options.patch_centres.empty() ? "" : " inside the patches") + "; need at least " +
                  std::to_string(options.min_correspondences));
  }
  Eigen::Vector3d source_origin = Eigen::Vector3d::Zero();
  for (const std::uint32_t i : considered) source_origin += source_positions.row(i).transpose();
  source_origin /= static_cast<double>(considered.size());
  Rigid3 shift_target = Rigid3::Identity(), shift_source = Rigid3::Identity();
  shift_target.translation() = -target.origin();
  shift_source.translation() = source_origin;
  Rigid3 T = shift_target * T_target_source_initial * shift_source;
  auto pose = [&] { return Rigid3(shift_target.inverse() * T * shift_source.inverse()); };

  // Coarse to fine: nested random samples (or voxels), gates shrinking level by level.
  const std::vector<IcpLevel> levels =
      IcpLevelsFor(options, static_cast<Eigen::Index>(considered.size()), target.spacing_mm());
  std::size_t largest = 0;
  for (const IcpLevel& l : levels) largest = std::max(largest, static_cast<std::size_t>(l.points));
  // The last level grows when it is the largest random sample and not yet every point.
  const bool grow = options.target_pose_sd_fraction > 0.0 && levels.back().points > 0 &&
                    static_cast<std::size_t>(levels.back().points) == largest && largest < considered.size();
  std::vector<std::uint32_t> rest;
  const std::vector<std::vector<std::uint32_t>> samples =
      LevelSamples(source_positions, considered, levels, grow ? &rest : nullptr);
  result.timings_s.Add("icp_samples", SecondsSince(start));

  Problem pb{&target,
             &source_positions,
             &source_normals,
             source_origin,
             &options,
             options.max_normal_angle_deg > 0.0 ? std::cos(options.max_normal_angle_deg / kDegPerRad) : -1.0,
             options.max_tangential_spacings > 0.0 && target.spacing_mm() > 0.0
                 ? std::pow(options.max_tangential_spacings * target.spacing_mm(), 2)
                 : std::numeric_limits<double>::infinity()};
  Pairs pairs;
  NearestCache cache;
  BlockSum last_sum;
  double length = 1.0, noise = 0.0;
  std::string failure;
  // What sampling adds to the pose's standard error (mm), sd sqrt(1 - n/N): the larger of the source
  // centroid's sd and the rotation's times the RMS lever, corrected for the finite source.
  const double N = static_cast<double>(considered.size());
  auto sampling_sd = [&](std::size_t n) {
    double rotation_sd_deg = 0.0, translation_sd_mm = 0.0;
    PoseSpread(last_sum, T.translation(), &rotation_sd_deg, &translation_sd_mm);
    const double sd = std::max(translation_sd_mm, rotation_sd_deg / kDegPerRad * length);
    return sd * std::sqrt(std::max(0.0, 1.0 - static_cast<double>(n) / N));
  };
  // Iterates one level (or one size of the last level's growing sample) on `sample` from the current
  // pose until the update falls below the tolerances (`small_update`: the last did); false with `failure`
  // set when the fit breaks down.
  // With `may_grow`, it stops early, setting `grow_to`, as soon as the sample costs more accuracy than
  // target_pose_sd_fraction allows: converging on a sample about to grow would be wasted work.
  std::size_t grow_to = 0;
  bool small_update = false;
  auto iterate = [&](std::size_t l, const std::vector<std::uint32_t>& sample, double rot_tol,
                     double trans_tol, bool may_grow, IcpLevelReport* report) {
    grow_to = 0;
    small_update = false;
    const IcpLevel& level = levels[l];
    Rigid3 previous = T;
    Vector6 x_previous = Vector6::Zero();
    for (int it = 0; it < level.max_iterations; ++it) {
      report->searches += FindPairs(pb, sample, T, level.max_distance_mm, &cache, &pairs);  // step 1
      double scale = 0.0, trim = 0.0;
      const std::int64_t count = RobustScale(options, &pairs, &scale, &trim);  // step 2
      if (count < options.min_correspondences) {
        failure = "only " + std::to_string(count) + " source points have a target point within " +
                  Format(level.max_distance_mm) + " mm at level " + std::to_string(l + 1) +
                  "; the surfaces do not overlap at this pose";
        return false;
      }
      const BlockSum sum = Accumulate(pb, pairs, scale, trim);  // step 3
      if (sum.count < options.min_correspondences) {
        failure = "the robust loss rejected all but " + std::to_string(sum.count) + " correspondences";
        return false;
      }
      noise = scale;
      length = std::max(std::sqrt(sum.arm2 / static_cast<double>(sum.count)), 1e-9);
      last_sum = sum;
      const Vector6 x = sum.H.ldlt().solve(-sum.g);
      if (!x.allFinite()) {
        failure = "the normal equations are singular at level " + std::to_string(l + 1) +
                  " (the overlap does not fix all six degrees of freedom)";
        return false;
      }
      const Vector6 step = options.extrapolate && it > 0 ? Extrapolated(x, x_previous, length) : x;  // 4a
      x_previous = x;
      const Rigid3 dT = Increment(step, options.method);  // step 4
      const Rigid3 before_previous = previous;
      previous = T;
      T = dT * T;
      ++report->iterations;
      ++result.iterations;
      report->rms_mm = std::sqrt(sum.weighted_r2 / sum.weight);
      // Stop on a small update, or on a two-step cycle between correspondence sets (the pose back where
      // it was two iterations ago): nearest-neighbour pairing is discrete, so ICP may alternate forever.
      if (may_grow) {
        const double allowed = options.target_pose_sd_fraction * noise;
        const double added = sampling_sd(sample.size());
        if (added > allowed) {
          const double sd = added / std::sqrt(1.0 - static_cast<double>(sample.size()) / N);
          grow_to = GrownSampleSize(sd, allowed, sample.size(), considered.size());
          break;
        }
      }
      const Rigid3 cycle = T * before_previous.inverse();
      small_update = RotationAngleDeg(dT.linear()) < rot_tol && dT.translation().norm() < trans_tol;
      if (small_update ||
          (it >= 2 && RotationAngleDeg(cycle.linear()) < rot_tol && cycle.translation().norm() < trans_tol)) {
        report->converged = true;
        break;
      }
    }
    return true;
  };
  // The finer levels search a grid of the target instead of its tree (the same answers): from the first
  // level whose search radius, and every later one's, is within kGridMaxSpacings target spacings, the grid's
  // cell the largest of those radii (docs/registration.md, "A grid for the finer levels").
  std::size_t grid_level = levels.size();
  double grid_cell = 0.0;
  if (target.spacing_mm() > 0.0) {
    for (std::size_t l = levels.size(); l-- > 0;) {
      const double radius = kSearchRadiusOverGate * levels[l].max_distance_mm;
      if (!(radius <= kGridMaxSpacings * target.spacing_mm())) break;
      grid_level = l;
      grid_cell = std::max(grid_cell, radius);
    }
  }
  // A target prepared for one alignment has a coarse sample: the levels before the grid's, whose search
  // radius is beyond five spacings of every point, search it instead (docs/registration.md, "A coarse
  // target for one alignment"); never the last level.
  const CoarseTarget* coarse = target.coarse();
  auto searches_coarse = [&](std::size_t l) {
    return coarse != nullptr && coarse->spacing_mm > 0.0 && l < grid_level && l + 1 < levels.size() &&
           kSearchRadiusOverGate * levels[l].max_distance_mm > kGridMaxSpacings * target.spacing_mm();
  };
  const double full_tangential2 = pb.max_tangential2;
  std::optional<RadiusGrid> grid;
  std::vector<std::uint32_t> grown;  // the last level's sample once it grows
  const std::vector<std::uint32_t>* sample = &samples.front();
  for (std::size_t l = 0; l < levels.size(); ++l) {
    const IcpLevel& level = levels[l];
    pb.coarse = searches_coarse(l) ? coarse : nullptr;
    // A point off the sample's nearest point along its plane by a sample spacing is not over a hole.
    pb.max_tangential2 = pb.coarse != nullptr && std::isfinite(full_tangential2)
                             ? std::pow(options.max_tangential_spacings * coarse->spacing_mm, 2)
                             : full_tangential2;
    if (l == grid_level) {
      const auto grid_start = std::chrono::steady_clock::now();
      grid = RadiusGrid::Build(target.centred_positions(), grid_cell * (1.0 + 1e-6),
                               kGridMaxCellsPerPoint * static_cast<std::size_t>(target.size()) + 4096);
      pb.grid = grid ? &*grid : nullptr;
      result.timings_s.Add("icp_grid", SecondsSince(grid_start));
    }
    sample = &samples[l];
    // Coarser levels need only bring the pose into the next level's reach: tolerances ten times looser
    // per level above the last.
    const double looser = std::pow(10.0, static_cast<double>(levels.size() - 1 - l));
    const double rot_tol = options.rotation_tolerance_deg * looser;
    const double trans_tol = options.translation_tolerance_mm * looser;
    // Random levels are nested (each sample a prefix of the next): their certificates carry over.
    const std::vector<std::uint32_t>* coarser = l > 0 ? &samples[l - 1] : nullptr;
    // (Not from the coarse sample's searches to every point's: a certificate speaks of the points searched.)
    const bool nested = coarser != nullptr && coarser->size() <= sample->size() &&
                        searches_coarse(l - 1) == searches_coarse(l) &&
                        std::equal(coarser->begin(), coarser->end(), sample->begin());
    std::size_t kept = nested ? coarser->size() : 0;
    std::size_t rest_used = 0;
    for (;;) {  // once, except for a growing last level
      IcpLevelReport report;
      report.voxel_size_mm = level.voxel_size_mm;
      report.max_distance_mm = level.max_distance_mm;
      report.source_points = static_cast<std::int64_t>(sample->size());
      report.target_points =
          pb.coarse != nullptr ? static_cast<std::int64_t>(pb.coarse->rows.size()) : target.size();
      cache.Reset(sample->size(), kSearchRadiusOverGate * level.max_distance_mm, kept);
      const bool may_grow = grow && l + 1 == levels.size() && rest_used < rest.size();
      const auto level_start = std::chrono::steady_clock::now();
      const bool ok = iterate(l, *sample, rot_tol, trans_tol, may_grow, &report);
      report.seconds = SecondsSince(level_start);
      result.levels.push_back(report);
      if (!ok) {
        result.T_target_source = pose();
        return finish(failure);
      }
      if (grow_to == 0) break;
      // Grow the sample while it costs accuracy (docs/registration.md, "Growing the last sample").
      const std::size_t next = std::min(grow_to, sample->size() + rest.size() - rest_used);
      if (grown.empty()) grown = *sample;
      kept = grown.size();
      const auto from = rest.begin() + static_cast<std::ptrdiff_t>(rest_used);
      rest_used += next - grown.size();
      grown.insert(grown.end(), from, rest.begin() + static_cast<std::ptrdiff_t>(rest_used));
      SortDistinctRows(grown.begin() + static_cast<std::ptrdiff_t>(kept), grown.end(),
                       static_cast<std::size_t>(source_positions.rows()));  // row order, as above
      sample = &grown;
    }
  }
  result.T_target_source = pose();
  result.converged = result.levels.back().converged;
  result.conditioning = Conditioning(last_sum.H, length);
  PoseSpread(last_sum, T.translation(), &result.rotation_sd_deg, &result.translation_sd_mm);
  result.residual_scale_mm = noise;
  result.sampling_sd_mm = sampling_sd(sample->size());

  // Final figures on the finest sample at the final pose; a poor fit is a failure with its reason.
  const double reach =
      options.inlier_distance_mm > 0.0 ? options.inlier_distance_mm : levels.back().max_distance_mm;
  // When the last iteration found its pairs within this reach and then moved the pose by less than the
  // tolerances (1e-3 degrees and 2 um by default), those pairs are the final figures: at the final pose the
  // RMS would differ by less than that movement, and a pair's inlier status only where its distance lies
  // within it of the reach. Otherwise the pairs are found again at the final pose; the last level's
  // certificates still hold for its sample and serve any reach up to their radius.
  if (!(small_update && reach == levels.back().max_distance_mm && pairs.r.size() == sample->size())) {
    const auto final_start = std::chrono::steady_clock::now();
    FindPairs(pb, *sample, T, reach, reach <= cache.radius ? &cache : nullptr, &pairs);
    result.timings_s.Add("icp_final_pairs", SecondsSince(final_start));
  }
  Summarise(&pairs, sample->size(), &result);
  const std::vector<std::string> problems = Problems(result, options, levels.back().max_iterations, reach);
  result.success = problems.empty();
  std::string message;
  if (result.success) {
    message = "converged in " + std::to_string(result.iterations) + " iterations: RMS " +
              Format(result.rms_mm) + " mm, " + Format(100.0 * result.inlier_fraction) + " % inliers";
  }
  for (const auto& p : problems) message += (message.empty() ? "" : "; ") + p;
  return finish(message);
}

}  // namespace pectus
