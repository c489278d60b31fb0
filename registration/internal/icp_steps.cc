// pectus: the steps of one ICP iteration (registration/internal/icp_steps.h). The method and its equations:
// docs/registration.md.
#include "registration/internal/icp_steps.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

#include "registration/internal/radius_grid.h"
#include "registration/robust_loss.h"

namespace pectus::icp_detail {
namespace {

// The k nearest target rows within `radius`: from the coarse sample's tree when the level searches it,
// else from the grid when there is one and the radius is within its reach (the same answers as the tree,
// faster), else from the tree over every point.
int NearestWithin(const Problem& pb, const Eigen::Vector3d& p, double radius, int k, std::uint32_t* indices,
                  double* squared_distances) {
  if (pb.coarse != nullptr) {
    const int found = pb.coarse->tree->NearestWithin(p, radius, k, indices, squared_distances);
    for (int h = 0; h < found; ++h) indices[h] = pb.coarse->rows[indices[h]];
    return found;
  }
  if (pb.grid != nullptr && radius <= pb.grid->max_radius()) {
    return pb.grid->NearestWithin(p, radius, k, indices, squared_distances);
  }
  return pb.target->tree().NearestWithin(p, radius, k, indices, squared_distances);
}

// The `want` nearest target rows of `p` within `gate`, nearest first, into `j` (their number into
// `found`; the nearest may lie beyond the gate when searched through the cache, for the caller's test),
// from the certificate when it still holds, else from the coarse sample, the grid or the tree (renewing
// the certificate). Returns true if it searched.
bool Nearest(const Problem& pb, const Eigen::Vector3d& p, double gate, std::size_t s, NearestCache* cache,
             int want, std::uint32_t* j, int* found) {
  constexpr int kMax = NearestCache::kMaxCandidates;
  static_assert(kMax + 1 <= KdTree3::kMaxBounded,
                "a certificate's search finds one more than its candidates");
  const Points3& target = pb.target->centred_positions();
  if (cache == nullptr) {
    double d2[kMax];
    *found = NearestWithin(pb, p, gate, want, j, d2);
    return true;
  }
  const int C = NearestCache::Candidates(want);
  if (cache->valid[s]) {
    const double moved = (p - cache->at[s]).norm();
    const int count = cache->count[s];
    // Any target point but the candidates is at least `others` away (triangle inequality).
    const double others = cache->reach[s] - moved;
    if (count == 0) {
      // No target point within `reach` of where it was: none within the gate while it has moved less
      // than reach - gate.
      if (others >= gate) {
        *found = 0;
        return false;
      }
    } else if (want == 1) {
      const auto& c = cache->candidates[s];
      int best = 0;
      double best2 = (target.row(c[0]).transpose() - p).squaredNorm();
      for (int k = 1; k < count; ++k) {
        const double d2 = (target.row(c[static_cast<std::size_t>(k)]).transpose() - p).squaredNorm();
        if (d2 < best2) {
          best2 = d2;
          best = k;
        }
      }
      if (others > 0.0 && best2 < others * others) {
        j[0] = c[static_cast<std::size_t>(best)];
        *found = 1;
        return false;
      }
    } else {
      // The candidates in order of their distance now; the nearest m of them are the nearest m target
      // points if the m-th is nearer than any other target point can be, and all of those within the gate
      // if fewer than `want` were candidates and no other target point can be within the gate.
      const auto& c = cache->candidates[s];
      std::uint32_t order[kMax];
      double d2[kMax];
      for (int k = 0; k < count; ++k) {
        const double d = (target.row(c[static_cast<std::size_t>(k)]).transpose() - p).squaredNorm();
        int at = k;
        for (; at > 0 && d2[at - 1] > d; --at) {
          d2[at] = d2[at - 1];
          order[at] = order[at - 1];
        }
        d2[at] = d;
        order[at] = c[static_cast<std::size_t>(k)];
      }
      const int m = std::min(want, count);
      if (others > 0.0 && d2[m - 1] < others * others && (m == want || others >= gate)) {
        int inside = 1;  // the nearest, whatever its distance (the caller gates it)
        while (inside < m && d2[inside] <= gate * gate) ++inside;
        std::copy(order, order + inside, j);
        *found = inside;
        return false;
      }
    }
  }
  std::uint32_t idx[kMax + 1];
  double d2[kMax + 1];
  const int hits = NearestWithin(pb, p, cache->radius, C + 1, idx, d2);
  cache->valid[s] = 1;
  cache->at[s] = p;
  cache->count[s] = static_cast<std::uint8_t>(std::min(hits, C));
  for (int k = 0; k < std::min(hits, C); ++k) cache->candidates[s][static_cast<std::size_t>(k)] = idx[k];
  cache->reach[s] = hits > C ? std::sqrt(d2[C]) : cache->radius;
  if (hits == 0) {
    *found = 0;
    return true;
  }
  int inside = 1;
  while (inside < std::min(hits, want) && d2[inside] <= gate * gate) ++inside;
  std::copy(idx, idx + inside, j);
  *found = inside;
  return true;
}

Eigen::Matrix3d SkewSymmetric(const Eigen::Vector3d& v) {
  Eigen::Matrix3d m;
  m << 0.0, -v.z(), v.y(), v.z(), 0.0, -v.x(), -v.y(), v.x(), 0.0;
  return m;
}

}  // namespace

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
  const int plane_points = pb.options->plane_points;
  pairs->Resize(sample.size());
  const auto m = static_cast<std::int64_t>(sample.size());
  std::int64_t searches = 0;
  const std::int64_t chunk = std::clamp(m / kMinChunks, kMinChunk, kChunk);
#pragma omp parallel for schedule(dynamic, chunk) reduction(+ : searches) if (m >= kMinParallelSearchPoints)
  for (std::int64_t k = 0; k < m; ++k) {
    const auto s = static_cast<std::size_t>(k);
    const std::uint32_t i = sample[s];
    const Eigen::Vector3d p = R * (pb.source->row(i).transpose() - pb.source_origin) + t;
    std::uint32_t near[NearestCache::kMaxCandidates];
    int found = 0;
    searches += Nearest(pb, p, gate, s, cache, plane_points, near, &found) ? 1 : 0;
    pairs->target[s] = kNoMatch;
    if (found == 0) continue;
    const std::uint32_t j = near[0];
    Eigen::Vector3d q = tp.row(j).transpose();
    if ((p - q).squaredNorm() > gate * gate) continue;
    Eigen::Vector3d n = tn.row(j).transpose();
    if (n.squaredNorm() == 0.0) continue;
    // A source point over a hole or beyond the edge of the target finds its nearest point on the rim, off
    // to the side; on the surface the nearest point lies about below it (Turk and Levoy 1994 drop pairs on
    // mesh boundaries for the same reason).
    const Eigen::Vector3d d = p - q;
    const double along = d.dot(n);
    if (d.squaredNorm() - along * along > pb.max_tangential2) continue;
    // The plane through the nearest target points (IcpOptions::plane_points); a border point has no normal.
    PlaneThroughNearestPoints(
        tp, tn, near, found, [&](std::uint32_t row) { return tn.row(row).squaredNorm() != 0.0; }, &q, &n);
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
#pragma omp parallel for schedule(dynamic, kChunk / kBlock) if (parallel)
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

}  // namespace pectus::icp_detail
