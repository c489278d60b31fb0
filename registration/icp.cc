// pectus: robust, gated, coarse-to-fine point-to-plane and symmetric ICP (registration/icp.h). The
// method and its equations: docs/registration.md.
#include "registration/icp.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <sstream>

#include "registration/random_sample.h"
#include "registration/voxel_downsample.h"
#include "shape/core/error.h"

namespace pectus {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDegPerRad = 180.0 / kPi;
constexpr std::uint32_t kNoMatch = std::numeric_limits<std::uint32_t>::max();
// Correspondences are summed in blocks of this many, then the blocks in order: the same sums for any
// number of threads.
constexpr std::size_t kBlock = 512;
// Steps 1 and 3 run on several threads only for at least this many sample points: a coarse level's few
// thousand points take less time than waking the threads, and on a busy machine every fork and join may
// wait for a time slice.
constexpr std::int64_t kMinParallelPoints = 16384;
// Step 1 searches this many times the gate, so that a certificate holds while a point moves a little.
constexpr double kSearchRadiusOverGate = 1.5;
// Step 2 estimates the robust scale from at most this many residuals.
constexpr std::size_t kScaleSamples = 16384;
// Step 4a extrapolates when two successive steps have at least this cosine, by at most this factor.
constexpr double kExtrapolationCosine = 0.8;
constexpr double kMaxExtrapolation = 4.0;

using Matrix6 = Eigen::Matrix<double, 6, 6>;
using Vector6 = Eigen::Matrix<double, 6, 1>;

double Seconds(std::chrono::steady_clock::time_point since) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - since).count();
}

std::string Format(double value, int precision = 3) {
  std::ostringstream s;
  s.precision(precision);
  s << value;
  return s.str();
}

// The normal equations of one block of correspondences.
struct BlockSum {
  Matrix6 H = Matrix6::Zero();
  Vector6 g = Vector6::Zero();
  double weighted_r2 = 0.0;
  double weight = 0.0;
  double arm2 = 0.0;  // sum of |p|^2 (mm^2): the lever of the rotation, for Conditioning
  std::int64_t count = 0;
};

// The correspondences of one level at the current pose (arrays indexed like the level's points).
struct Pairs {
  std::vector<std::uint32_t> target;  // kNoMatch when dropped
  std::vector<Eigen::Vector3d> p;     // transformed source point (target's centred frame)
  std::vector<Eigen::Vector3d> n;     // normal of the residual (target's, or the symmetric one)
  std::vector<double> r;              // signed residual along n (mm)
  std::vector<double> abs_r;          // scratch of step 2
  void Resize(std::size_t m) {
    target.resize(m);
    p.resize(m);
    n.resize(m);
    r.resize(m);
  }
};

// Everything one alignment needs, shared by the steps below.
struct Problem {
  const IcpTarget* target;
  const Points3* source;          // original positions
  const Points3* source_normals;  // may be empty
  Eigen::Vector3d source_origin;  // subtracted from source positions before the pose is applied
  const IcpOptions* options;
  double cos_max_normal_angle;  // -1 when the normal test is off
  double max_tangential2;       // squared tangential reach (mm^2); infinity when off
};

// The correspondence certificates of one level: per sample point, where it was when last searched, its
// nearest target row there (kNoMatch: none within `radius`) and the distances to the nearest and second
// nearest target points (mm; `radius` when missing). A point that has since moved by less than half the
// gap between them provably keeps the same nearest point, so step 1 searches the tree only for the points
// whose certificate has expired: exact nearest neighbours at a fraction of the searches.
struct NearestCache {
  double radius = 0.0;  // search radius (mm), above the gate
  std::vector<Eigen::Vector3d> at;
  std::vector<std::uint32_t> nearest;
  std::vector<double> d1, d2;
  std::vector<std::uint8_t> valid;
  void Reset(std::size_t m, double search_radius) {
    radius = search_radius;
    at.resize(m);
    nearest.resize(m);
    d1.resize(m);
    d2.resize(m);
    valid.assign(m, 0);
  }
};

// The nearest target row of `p` (kNoMatch if none within the cache's radius), from the certificate when it
// still holds, else from the tree (updating the certificate). Returns true if it searched the tree.
bool Nearest(const KdTree3& tree, const Eigen::Vector3d& p, double gate, std::size_t s, NearestCache* cache,
             std::uint32_t* j) {
  if (cache == nullptr) {
    double d2 = 0.0;
    if (!tree.NearestWithin(p, gate, j, &d2)) *j = kNoMatch;
    return true;
  }
  if (cache->valid[s]) {
    const double moved = (p - cache->at[s]).norm();
    if (cache->nearest[s] == kNoMatch ? moved <= cache->radius - gate
                                      : 2.0 * moved < cache->d2[s] - cache->d1[s]) {
      *j = cache->nearest[s];
      return false;
    }
  }
  std::uint32_t idx[2] = {kNoMatch, kNoMatch};
  double d2[2] = {0.0, 0.0};
  const int found = tree.NearestTwoWithin(p, cache->radius, idx, d2);
  cache->valid[s] = 1;
  cache->at[s] = p;
  cache->nearest[s] = found > 0 ? idx[0] : kNoMatch;
  cache->d1[s] = found > 0 ? std::sqrt(d2[0]) : cache->radius;
  cache->d2[s] = found > 1 ? std::sqrt(d2[1]) : cache->radius;
  *j = cache->nearest[s];
  return true;
}

// Step 1: nearest target point of every sample point within `gate`, and the residual along the normal.
// Returns the number of tree searches.
std::int64_t FindPairs(const Problem& pb, const std::vector<std::uint32_t>& sample, const Rigid3& T,
                       double gate, NearestCache* cache, Pairs* pairs) {
  const Eigen::Matrix3d R = T.linear();
  const Eigen::Vector3d t = T.translation();
  const bool symmetric = pb.options->method == IcpMethod::kSymmetric;
  const bool use_source_normals =
      pb.source_normals->rows() > 0 && (symmetric || pb.cos_max_normal_angle > -1.0);
  const Points3& tp = pb.target->centred_positions();
  const Points3& tn = pb.target->normals();
  pairs->Resize(sample.size());
  const auto m = static_cast<std::int64_t>(sample.size());
  std::int64_t searches = 0;
#pragma omp parallel for schedule(static) reduction(+ : searches) if (m >= kMinParallelPoints)
  for (std::int64_t k = 0; k < m; ++k) {
    const auto s = static_cast<std::size_t>(k);
    const std::uint32_t i = sample[s];
    const Eigen::Vector3d p = R * (pb.source->row(i).transpose() - pb.source_origin) + t;
    std::uint32_t j = kNoMatch;
    searches += Nearest(pb.target->tree(), p, gate, s, cache, &j) ? 1 : 0;
    pairs->target[s] = kNoMatch;
    if (j == kNoMatch) continue;
    const Eigen::Vector3d q = tp.row(j).transpose();
    if ((p - q).squaredNorm() > gate * gate) continue;
    Eigen::Vector3d n = tn.row(j).transpose();
    if (n.squaredNorm() == 0.0) continue;
    // A source point over a hole or beyond the edge of the target finds its nearest point on the rim, off
    // to the side; on the surface the nearest point lies about below it (Turk and Levoy 1994 drop pairs on
    // mesh boundaries for the same reason).
    const Eigen::Vector3d d = p - q;
    const double along = d.dot(n);
    if (d.squaredNorm() - along * along > pb.max_tangential2) continue;
    if (use_source_normals) {
      Eigen::Vector3d ns = R * pb.source_normals->row(i).transpose();
      if (ns.squaredNorm() == 0.0) continue;
      const double c = ns.dot(n);
      if (std::abs(c) < pb.cos_max_normal_angle) continue;
      if (symmetric) {
        // Rusinkiewicz (2019), Eq. (6): the sum of both normals, flipped to agree; normalised so that the
        // residual stays a distance in mm.
        if (c < 0.0) ns = -ns;
        n = (n + ns).normalized();
      }
    }
    pairs->target[s] = j;
    pairs->p[s] = p;
    pairs->n[s] = n;
    pairs->r[s] = (p - q).dot(n);  // Chen and Medioni (1992): distance to the target's tangent plane
  }
  return searches;
}

// Step 2: the robust scale (MAD of the residuals) and the trimming threshold. Returns how many pairs.
// The MAD is taken over at most kScaleSamples residuals picked at a fixed stride (its relative standard
// error is then about 1 %); the trimming quantile over all of them.
std::int64_t RobustScale(const IcpOptions& options, Pairs* pairs, double* scale, double* trim_threshold) {
  const std::size_t m = pairs->r.size();
  std::int64_t count = 0;
  for (std::size_t k = 0; k < m; ++k) count += pairs->target[k] != kNoMatch;
  const bool trim = options.trim_fraction > 0.0;
  const std::size_t stride =
      trim ? 1 : std::max<std::size_t>(1, static_cast<std::size_t>(count) / kScaleSamples);
  std::vector<double>& abs_r = pairs->abs_r;
  abs_r.clear();
  for (std::size_t k = 0, matched = 0; k < m; ++k) {
    if (pairs->target[k] != kNoMatch && matched++ % stride == 0) abs_r.push_back(std::abs(pairs->r[k]));
  }
  *trim_threshold = std::numeric_limits<double>::infinity();
  if (count > 0 && trim) {
    const auto keep =
        static_cast<std::size_t>(std::ceil((1.0 - options.trim_fraction) * static_cast<double>(count)));
    auto nth = abs_r.begin() + static_cast<std::ptrdiff_t>(std::max<std::size_t>(keep, 1) - 1);
    std::nth_element(abs_r.begin(), nth, abs_r.end());
    *trim_threshold = *nth;
  }
  *scale = std::max(MadScale(&abs_r), options.min_robust_scale_mm);
  return count;
}

// Step 3: the weighted normal equations H x = -g of the linearised residuals, Chen and Medioni (1992)
// for point-to-plane (J = [p x n, n]) and Rusinkiewicz (2019), Eq. (9), for symmetric (J = [(p+q) x n, n]).
BlockSum Accumulate(const Problem& pb, const Pairs& pairs, double scale, double trim_threshold) {
  const IcpOptions& o = *pb.options;
  const double c = RobustTuningConstant(o.loss) * scale;
  const bool symmetric = o.method == IcpMethod::kSymmetric;
  const Points3& tp = pb.target->centred_positions();
  const std::size_t m = pairs.r.size();
  const std::size_t blocks = (m + kBlock - 1) / kBlock;
  std::vector<BlockSum> sums(blocks);
  const bool parallel = static_cast<std::int64_t>(m) >= kMinParallelPoints;
#pragma omp parallel for schedule(static) if (parallel)
  for (std::int64_t b = 0; b < static_cast<std::int64_t>(blocks); ++b) {
    BlockSum& s = sums[static_cast<std::size_t>(b)];
    const std::size_t end = std::min(m, (static_cast<std::size_t>(b) + 1) * kBlock);
    for (std::size_t k = static_cast<std::size_t>(b) * kBlock; k < end; ++k) {
      if (pairs.target[k] == kNoMatch || std::abs(pairs.r[k]) > trim_threshold) continue;
      const double r = pairs.r[k];
      const double w = RobustWeight(o.loss, r, c);
      if (w <= 0.0) continue;
      const Eigen::Vector3d& n = pairs.n[k];
      const Eigen::Vector3d arm =
          symmetric ? Eigen::Vector3d(pairs.p[k] + tp.row(pairs.target[k]).transpose()) : pairs.p[k];
      Vector6 J;
      J << arm.cross(n), n;
      s.H.noalias() += w * J * J.transpose();
      s.g.noalias() += (w * r) * J;
      s.weighted_r2 += w * r * r;
      s.weight += w;
      s.arm2 += pairs.p[k].squaredNorm();
      ++s.count;
    }
  }
  BlockSum total;
  for (const BlockSum& s : sums) {
    total.H += s.H;
    total.g += s.g;
    total.weighted_r2 += s.weighted_r2;
    total.weight += s.weight;
    total.arm2 += s.arm2;
    total.count += s.count;
  }
  return total;
}

// Smallest over largest eigenvalue of H with the rotation rows scaled by a length, so that rotation
// (mm per radian) and translation (mm per mm) are comparable. Near 0: a sliding direction.
double Conditioning(const Matrix6& H, double length) {
  Vector6 d;
  d << Eigen::Vector3d::Constant(1.0 / length), Eigen::Vector3d::Ones();
  const Matrix6 Hs = d.asDiagonal() * H * d.asDiagonal();
  Eigen::SelfAdjointEigenSolver<Matrix6> eig(Hs, Eigen::EigenvaluesOnly);
  const double hi = eig.eigenvalues()(5);
  return hi > 0.0 ? std::max(0.0, eig.eigenvalues()(0)) / hi : 0.0;
}

Eigen::Matrix3d SkewSymmetric(const Eigen::Vector3d& v) {
  Eigen::Matrix3d m;
  m << 0.0, -v.z(), v.y(), v.z(), 0.0, -v.x(), -v.y(), v.x(), 0.0;
  return m;
}

// The spread of the pose that the residuals imply: Cov(x) = s^2 H^-1 for the solution x = (w, t) of
// (ICP-1), s^2 the weighted residual variance; the rotation's largest standard deviation (degrees) and the
// largest standard deviation of the position of `at` (mm), which moves by w x at + t.
void PoseSpread(const BlockSum& sum, const Eigen::Vector3d& at, double* rotation_sd_deg,
                double* translation_sd_mm) {
  *rotation_sd_deg = *translation_sd_mm = std::numeric_limits<double>::infinity();
  if (!(sum.weight > 0.0) || sum.count <= 6) return;
  const double s2 =
      sum.weighted_r2 / sum.weight * static_cast<double>(sum.count) / static_cast<double>(sum.count - 6);
  const Eigen::LDLT<Matrix6> ldlt(sum.H);
  if (ldlt.info() != Eigen::Success) return;
  const Matrix6 cov = s2 * ldlt.solve(Matrix6::Identity());
  if (!cov.allFinite()) return;
  Eigen::Matrix<double, 3, 6> J;
  J << -SkewSymmetric(at), Eigen::Matrix3d::Identity();
  const Eigen::Matrix3d cov_rotation = cov.topLeftCorner<3, 3>();
  const Eigen::Matrix3d cov_at = J * cov * J.transpose();
  *rotation_sd_deg =
      std::sqrt(
          std::max(0.0, Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(cov_rotation).eigenvalues()(2))) *
      kDegPerRad;
  *translation_sd_mm =
      std::sqrt(std::max(0.0, Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(cov_at).eigenvalues()(2)));
}

// Step 4: the incremental pose from the solution x of the normal equations.
Rigid3 Increment(const Vector6& x, IcpMethod method) {
  Rigid3 dT = Rigid3::Identity();
  const Eigen::Vector3d a = x.head<3>();
  const double norm = a.norm();
  if (method == IcpMethod::kPointToPlane) {
    if (norm > 0.0) dT.linear() = Eigen::AngleAxisd(norm, a / norm).toRotationMatrix();
    dT.translation() = x.tail<3>();
    return dT;
  }
  // Rusinkiewicz (2019), Sec. 3.2: x = (a tan(theta), t / cos(theta)); the update is R T(t) R with R the
  // rotation by theta about a (half of the rotation applied to each surface).
  const double theta = std::atan(norm);
  Rigid3 half = Rigid3::Identity();
  if (norm > 0.0) half.linear() = Eigen::AngleAxisd(theta, a / norm).toRotationMatrix();
  Rigid3 shift = Rigid3::Identity();
  shift.translation() = x.tail<3>() * std::cos(theta);
  return half * shift * half;
}

// Step 4a: near convergence ICP moves linearly: each step a fraction rho of the last, in the same
// direction (nearest-neighbour pairing on noisy surfaces pulls every residual toward zero). When two
// successive solutions agree in direction (cosine above kExtrapolationCosine, the rotation scaled by the
// lever `length` so that both parts are in mm), the rest of the geometric series, x (1 + rho + rho^2 + ...)
// = x / (1 - rho), is taken at once, at most kMaxExtrapolation times x (Aitken's delta-squared process).
Vector6 Extrapolated(const Vector6& x, const Vector6& previous, double length) {
  Vector6 a = x, b = previous;
  a.head<3>() *= length;
  b.head<3>() *= length;
  const double na = a.norm(), nb = b.norm();
  if (!(na > 0.0 && nb > 0.0)) return x;
  const double rho = na / nb;
  if (a.dot(b) < kExtrapolationCosine * na * nb || rho >= 1.0) return x;
  return x * std::min(1.0 / (1.0 - rho), kMaxExtrapolation);
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

// The source sample of every level, finest last. Random levels are prefixes of one shuffle (nested);
// voxel levels subsample the next finer level's sample.
std::vector<std::vector<std::uint32_t>> LevelSamples(const Points3& source,
                                                     const std::vector<std::uint32_t>& rows,
                                                     const std::vector<IcpLevel>& levels) {
  std::size_t most = 0;
  for (const IcpLevel& l : levels) most = std::max(most, static_cast<std::size_t>(l.points));
  const std::vector<std::uint32_t> shuffled =
      most > 0 ? RandomSample(rows, most) : std::vector<std::uint32_t>();
  std::vector<std::vector<std::uint32_t>> samples(levels.size());
  for (std::size_t l = levels.size(); l-- > 0;) {
    const std::vector<std::uint32_t>& finer = l + 1 < levels.size() ? samples[l + 1] : rows;
    if (levels[l].points > 0) {
      const std::size_t count = std::min(shuffled.size(), static_cast<std::size_t>(levels[l].points));
      samples[l].assign(shuffled.begin(), shuffled.begin() + static_cast<std::ptrdiff_t>(count));
    } else if (levels[l].voxel_size_mm > 0.0) {
      samples[l] = VoxelDownsample(source, levels[l].voxel_size_mm, &finer);
    } else {
      samples[l] = finer;
    }
  }
  return samples;
}

// Inliers (a target point within `reach`) among the sample at pose T, and their RMS point-to-plane
// distance.
void Evaluate(const Problem& pb, const std::vector<std::uint32_t>& sample, const Rigid3& T, double reach,
              NearestCache* cache, Pairs* pairs, IcpResult* result) {
  FindPairs(pb, sample, T, reach, cache, pairs);
  double r2 = 0.0;
  result->inliers = 0;
  for (std::size_t k = 0; k < pairs->r.size(); ++k) {
    if (pairs->target[k] == kNoMatch) continue;
    ++result->inliers;
    r2 += pairs->r[k] * pairs->r[k];
  }
  result->inlier_fraction =
      sample.empty() ? 0.0 : static_cast<double>(result->inliers) / static_cast<double>(sample.size());
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
    result.seconds = Seconds(start);
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
  const std::vector<std::vector<std::uint32_t>> samples = LevelSamples(source_positions, considered, levels);

  const Problem pb{
      &target,
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
  double length = 1.0;
  for (std::size_t l = 0; l < levels.size(); ++l) {
    const IcpLevel& level = levels[l];
    const std::vector<std::uint32_t>& sample = samples[l];
    // Coarser levels need only bring the pose into the next level's reach: tolerances ten times looser
    // per level above the last.
    const double looser = std::pow(10.0, static_cast<double>(levels.size() - 1 - l));
    const double rot_tol = options.rotation_tolerance_deg * looser;
    const double trans_tol = options.translation_tolerance_mm * looser;
    IcpLevelReport report;
    report.voxel_size_mm = level.voxel_size_mm;
    report.max_distance_mm = level.max_distance_mm;
    report.source_points = static_cast<std::int64_t>(sample.size());
    cache.Reset(sample.size(), kSearchRadiusOverGate * level.max_distance_mm);
    Rigid3 previous = T;
    Vector6 x_previous = Vector6::Zero();
    for (int it = 0; it < level.max_iterations; ++it) {
      report.searches += FindPairs(pb, sample, T, level.max_distance_mm, &cache, &pairs);  // step 1
      double scale = 0.0, trim = 0.0;
      const std::int64_t count = RobustScale(options, &pairs, &scale, &trim);  // step 2
      if (count < options.min_correspondences) {
        result.levels.push_back(report);
        result.T_target_source = pose();
        return finish("only " + std::to_string(count) + " source points have a target point within " +
                      Format(level.max_distance_mm) + " mm at level " + std::to_string(l + 1) +
                      "; the surfaces do not overlap at this pose");
      }
      const BlockSum sum = Accumulate(pb, pairs, scale, trim);  // step 3
      if (sum.count < options.min_correspondences) {
        result.levels.push_back(report);
        result.T_target_source = pose();
        return finish("the robust loss rejected all but " + std::to_string(sum.count) + " correspondences");
      }
      length = std::max(std::sqrt(sum.arm2 / static_cast<double>(sum.count)), 1e-9);
      last_sum = sum;
      const Vector6 x = sum.H.ldlt().solve(-sum.g);
      if (!x.allFinite()) {
        result.levels.push_back(report);
        result.T_target_source = pose();
        return finish("the normal equations are singular at level " + std::to_string(l + 1) +
                      " (the overlap does not fix all six degrees of freedom)");
      }
      const Vector6 step = options.extrapolate && it > 0 ? Extrapolated(x, x_previous, length) : x;  // 4a
      x_previous = x;
      const Rigid3 dT = Increment(step, options.method);  // step 4
      const Rigid3 before_previous = previous;
      previous = T;
      T = dT * T;
      ++report.iterations;
      ++result.iterations;
      report.rms_mm = std::sqrt(sum.weighted_r2 / sum.weight);
      // Stop on a small update, or on a two-step cycle between correspondence sets (the pose back where
      // it was two iterations ago): nearest-neighbour pairing is discrete, so ICP may alternate forever.
      const Rigid3 cycle = T * before_previous.inverse();
      if ((RotationAngleDeg(dT.linear()) < rot_tol && dT.translation().norm() < trans_tol) ||
          (it >= 2 && RotationAngleDeg(cycle.linear()) < rot_tol && cycle.translation().norm() < trans_tol)) {
        report.converged = true;
        break;
      }
    }
    result.levels.push_back(report);
  }
  result.T_target_source = pose();
  result.converged = result.levels.back().converged;
  result.conditioning = Conditioning(last_sum.H, length);
  PoseSpread(last_sum, T.translation(), &result.rotation_sd_deg, &result.translation_sd_mm);

  // Final figures on the finest sample at the final pose; a poor fit is a failure with its reason.
  const double reach =
      options.inlier_distance_mm > 0.0 ? options.inlier_distance_mm : levels.back().max_distance_mm;
  // The last level's certificates still hold for its sample; they serve any reach up to their radius.
  Evaluate(pb, samples.back(), T, reach, reach <= cache.radius ? &cache : nullptr, &pairs, &result);
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
