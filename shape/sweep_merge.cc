#include "shape/sweep_merge.h"

#include <ceres/ceres.h>
#include <ceres/rotation.h>
#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <functional>
#include <numeric>
#include <queue>

#include "registration/kdtree.h"
#include "registration/normals.h"
#include "registration/voxel_downsample.h"
#include "shape/core/error.h"
#include "shape/core/log.h"

namespace pectus {
namespace {

using Clock = std::chrono::steady_clock;
double Since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

double AngleDeg(const Eigen::Matrix3d& R) {
  const double c = std::clamp((R.trace() - 1.0) / 2.0, -1.0, 1.0);
  return std::acos(c) * 180.0 / M_PI;
}

// One sweep, prepared once: normals and an ICP target in the sweep's own frame, and a voxel subsample.
struct Sweep {
  const PointCloud* cloud = nullptr;
  Points3 normals;                          // sweep frame
  std::unique_ptr<IcpTarget> target;        // sweep frame (centred inside)
  std::vector<std::uint32_t> samples;       // rows of the voxel subsample
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
};

// A correspondence of the joint solve: point p of sweep j lies on the tangent plane (q, n) of sweep i.
struct Correspondence {
  std::size_t i, j;
  Eigen::Vector3d p, q, n;  // p in sweep j's frame; q, n in sweep i's frame
};

// Residual (R_i n) . (R_j p + t_j - R_i q - t_i) with poses as (unit quaternion x,y,z,w; translation).
struct PointToPlaneResidual {
  PointToPlaneResidual(const Eigen::Vector3d& p, const Eigen::Vector3d& q, const Eigen::Vector3d& n)
      : p_(p), q_(q), n_(n) {}
  template <typename T>
  bool operator()(const T* qi, const T* ti, const T* qj, const T* tj, T* residual) const {
    using Quat = Eigen::Quaternion<T>;
    using Vec = Eigen::Matrix<T, 3, 1>;
    const Eigen::Map<const Quat> Ri(qi), Rj(qj);
    const Eigen::Map<const Vec> Ti(ti), Tj(tj);
    const Vec world_p = Rj * p_.cast<T>() + Tj;
    const Vec world_q = Ri * q_.cast<T>() + Ti;
    const Vec world_n = Ri * n_.cast<T>();
    residual[0] = world_n.dot(world_p - world_q);
    return true;
  }
  static ceres::CostFunction* Create(const Correspondence& c) {
    return new ceres::AutoDiffCostFunction<PointToPlaneResidual, 1, 4, 3, 4, 3>(
        new PointToPlaneResidual(c.p, c.q, c.n));
  }
  Eigen::Vector3d p_, q_, n_;
};

// Gated correspondences from (evenly strided) samples of sweep j onto sweep i at the given poses.
std::vector<Correspondence> FindCorrespondences(const std::vector<Sweep>& sweeps, const std::vector<Rigid3>& P,
                                                std::size_t i, std::size_t j, int max_samples, double gate_mm) {
  const Sweep& a = sweeps[i];
  const Sweep& b = sweeps[j];
  const Rigid3 T_i_j = P[i].inverse() * P[j];
  const std::size_t n = b.samples.size();
  const std::size_t stride = std::max<std::size_t>(1, n / static_cast<std::size_t>(std::max(1, max_samples)));
  std::vector<Correspondence> out;
  const double gate2 = gate_mm * gate_mm;
  for (std::size_t s = 0; s < n; s += stride) {
    const Eigen::Vector3d p = b.cloud->positions.row(b.samples[s]).transpose();
    const Eigen::Vector3d in_i = T_i_j * p - a.target->origin();
    std::uint32_t k;
    double d2;
    if (!a.target->tree().Nearest(in_i, &k, &d2) || d2 > gate2) continue;
    const Eigen::Vector3d nq = a.normals.row(k).transpose();
    if (nq.squaredNorm() < 0.5) continue;
    const Eigen::Vector3d np = T_i_j.linear() * b.normals.row(b.samples[s]).transpose();
    if (np.squaredNorm() > 0.5 && std::abs(np.dot(nq)) < std::cos(45.0 * M_PI / 180.0)) continue;
    out.push_back({i, j, p, a.target->centred_positions().row(k).transpose() + a.target->origin(), nq});
  }
  return out;
}

double RmsPointToPlane(const std::vector<Correspondence>& cs, const std::vector<Rigid3>& P) {
  if (cs.empty()) return 0.0;
  double sum = 0;
  for (const auto& c : cs) {
    const double r = (P[c.i].linear() * c.n).dot(P[c.j] * c.p - P[c.i] * c.q);
    sum += r * r;
  }
  return std::sqrt(sum / static_cast<double>(cs.size()));
}

struct Link {
  std::size_t i, j;
  double overlap;
};

}  // namespace

bool SweepMergeOptions::IsValid(std::string* why) const {
  auto fail = [&](const std::string& m) {
    if (why) *why = m;
    return false;
  };
  if (!(overlap_distance_mm > 0)) return fail("overlap distance must be > 0 mm");
  if (min_overlap_fraction < 0 || min_overlap_fraction >= 1) return fail("minimum overlap must be in [0, 1)");
  if (global_rounds < 0 || global_points_per_pair < 10) return fail("global rounds >= 0 and points per pair >= 10");
  if (global_max_distance_mm < 0) return fail("global gate must be >= 0");
  if (smoothing_mm < 0) return fail("smoothing must be >= 0 mm");
  if (outlier_neighbours < 0 || outlier_std_ratio <= 0) return fail("outlier neighbours >= 0 and ratio > 0");
  if (target_spacing_mm < 0) return fail("target spacing must be >= 0 mm");
  return pairwise.IsValid(why);
}

SweepMergeResult MergeSweeps(const std::vector<PointCloud>& clouds, const std::vector<Rigid3>& start,
                             const SweepMergeOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) ThrowUsage("merge options: " + why);
  if (clouds.empty()) ThrowBadInput("sweeps", "no sweeps to merge");
  if (clouds.size() != start.size()) {
    ThrowBadInput("poses", std::to_string(start.size()) + " poses for " + std::to_string(clouds.size()) + " sweeps");
  }
  if (options.anchor >= clouds.size()) ThrowUsage("anchor sweep " + std::to_string(options.anchor) + " does not exist");
  const std::size_t n = clouds.size();
  SweepMergeResult result;

  // 1. Normals, ICP targets and subsamples of every sweep, in its own frame.
  auto t0 = Clock::now();
  std::vector<Sweep> sweeps(n);
  for (std::size_t s = 0; s < n; ++s) {
    const PointCloud& c = clouds[s];
    if (c.size() < 10) ThrowBadInput("sweep " + std::to_string(s), "has " + std::to_string(c.size()) + " points (< 10)");
    c.Validate("sweep " + std::to_string(s));
    Sweep& w = sweeps[s];
    w.cloud = &c;
    NormalOptions no;
    no.orientation = NormalOrientation::kPropagate;
    w.normals = EstimateNormals(c.positions, no).normals;
    w.target = std::make_unique<IcpTarget>(c.positions, w.normals, "sweep " + std::to_string(s));
    w.centroid = c.positions.colwise().mean().transpose();
    w.samples = VoxelDownsample(c.positions, std::max(1.0, 2.0 * w.target->spacing_mm()));
    result.points_in += c.size();
  }
  double spacing = 0;
  for (const auto& w : sweeps) spacing += w.target->spacing_mm() / static_cast<double>(n);
  result.seconds_normals = Since(t0);

  // Work in a world frame centred on the data, so that far-from-origin scans keep their precision.
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  for (std::size_t s = 0; s < n; ++s) centre += start[s] * sweeps[s].centroid / static_cast<double>(n);
  Rigid3 T_centred_world = Rigid3::Identity();
  T_centred_world.translation() = -centre;
  std::vector<Rigid3> P(n);
  for (std::size_t s = 0; s < n; ++s) P[s] = T_centred_world * start[s];

  // 2. Which sweeps overlap, at the starting poses.
  t0 = Clock::now();
  std::vector<Link> links;
  {
    std::vector<Points3> world(n);
    std::vector<std::unique_ptr<KdTree3>> trees(n);
    for (std::size_t s = 0; s < n; ++s) {
      const auto& idx = sweeps[s].samples;
      world[s].resize(static_cast<Eigen::Index>(idx.size()), 3);
      for (std::size_t k = 0; k < idx.size(); ++k) {
        world[s].row(static_cast<Eigen::Index>(k)) = (P[s] * clouds[s].positions.row(idx[k]).transpose()).transpose();
      }
      trees[s] = std::make_unique<KdTree3>(world[s]);
    }
    const double d2max = options.overlap_distance_mm * options.overlap_distance_mm;
    auto fraction = [&](std::size_t a, std::size_t b) {  // of a's samples near b
      std::size_t hits = 0;
      for (Eigen::Index k = 0; k < world[a].rows(); ++k) {
        std::uint32_t idx;
        double d2;
        if (trees[b]->Nearest(world[a].row(k).transpose(), &idx, &d2) && d2 <= d2max) ++hits;
      }
      return static_cast<double>(hits) / static_cast<double>(std::max<Eigen::Index>(1, world[a].rows()));
    };
    std::vector<Link> all;
    for (std::size_t i = 0; i < n; ++i) {
      for (std::size_t j = i + 1; j < n; ++j) all.push_back({i, j, 0.0});
    }
#pragma omp parallel for schedule(dynamic)
    for (std::size_t k = 0; k < all.size(); ++k) {
      all[k].overlap = std::max(fraction(all[k].i, all[k].j), fraction(all[k].j, all[k].i));
    }
    for (const auto& l : all) {
      if (l.overlap >= options.min_overlap_fraction) links.push_back(l);
    }
  }
  result.seconds_overlap = Since(t0);
  if (n > 1) {
    for (std::size_t s = 0; s < n; ++s) {
      const bool linked = std::any_of(links.begin(), links.end(), [&](const Link& l) { return l.i == s || l.j == s; });
      if (!linked) {
        ThrowFailure("sweep " + std::to_string(s) + " overlaps no other sweep (within " +
                     std::to_string(options.overlap_distance_mm) + " mm at the starting poses); give better "
                     "starting poses or a larger --overlap-distance");
      }
    }
  }

  const double gate = options.global_max_distance_mm > 0 ? options.global_max_distance_mm : 4.0 * spacing;
  std::vector<std::vector<Correspondence>> before(links.size());
  for (std::size_t k = 0; k < links.size(); ++k) {
    before[k] = FindCorrespondences(sweeps, P, links[k].i, links[k].j, options.global_points_per_pair,
                                    std::max(gate, options.overlap_distance_mm));
  }

  std::vector<bool> pairwise_ok(links.size(), false);
  if (options.refine_poses && n > 1) {
    // 3. Pairwise ICP on every linked pair: T_i_j, sweep j into sweep i.
    t0 = Clock::now();
    std::vector<Rigid3> relative(links.size());
    {
      Progress progress("pairwise alignment", static_cast<std::int64_t>(links.size()));
      for (std::size_t k = 0; k < links.size(); ++k) {
        const auto [i, j, overlap] = links[k];
        const IcpResult r = AlignIcp(*sweeps[i].target, clouds[j].positions, sweeps[j].normals, P[i].inverse() * P[j],
                                     options.pairwise);
        relative[k] = r.T_target_source;
        pairwise_ok[k] = r.success;
        progress.Advance();
      }
    }
    // Starting poses from a maximum spanning tree of the good pairs (by overlap), grown from the anchor.
    {
      std::vector<bool> placed(n, false);
      placed[options.anchor] = true;
      using Item = std::pair<double, std::size_t>;  // overlap, link
      std::priority_queue<Item> queue;
      auto push_links = [&](std::size_t s) {
        for (std::size_t k = 0; k < links.size(); ++k) {
          if (pairwise_ok[k] && (links[k].i == s || links[k].j == s)) queue.push({links[k].overlap, k});
        }
      };
      push_links(options.anchor);
      while (!queue.empty()) {
        const std::size_t k = queue.top().second;
        queue.pop();
        const auto [i, j, overlap] = links[k];
        if (placed[i] == placed[j]) continue;
        if (placed[i]) {
          P[j] = P[i] * relative[k];
          placed[j] = true;
          push_links(j);
        } else {
          P[i] = P[j] * relative[k].inverse();
          placed[i] = true;
          push_links(i);
        }
      }
    }
    result.seconds_pairwise = Since(t0);

    // 4. Joint point-to-plane adjustment of all poses (Ceres), a few rounds of correspondence search.
    t0 = Clock::now();
    Progress progress("global adjustment", options.global_rounds);
    for (int round = 0; round < options.global_rounds; ++round) {
      std::vector<std::vector<Correspondence>> found(links.size());
#pragma omp parallel for schedule(dynamic)
      for (std::size_t k = 0; k < links.size(); ++k) {
        found[k] = FindCorrespondences(sweeps, P, links[k].i, links[k].j, options.global_points_per_pair, gate);
        auto back = FindCorrespondences(sweeps, P, links[k].j, links[k].i, options.global_points_per_pair, gate);
        found[k].insert(found[k].end(), back.begin(), back.end());
      }
      std::vector<Eigen::Quaterniond> q(n);
      std::vector<Eigen::Vector3d> t(n);
      for (std::size_t s = 0; s < n; ++s) {
        q[s] = Eigen::Quaterniond(P[s].linear()).normalized();
        t[s] = P[s].translation();
      }
      // Robust scale from the residuals' median absolute deviation.
      std::vector<double> abs_r;
      for (const auto& f : found) {
        for (const auto& c : f) abs_r.push_back(std::abs((P[c.i].linear() * c.n).dot(P[c.j] * c.p - P[c.i] * c.q)));
      }
      if (abs_r.size() < 20) break;
      std::nth_element(abs_r.begin(), abs_r.begin() + static_cast<std::ptrdiff_t>(abs_r.size() / 2), abs_r.end());
      const double sigma = std::max(0.02, 1.4826 * abs_r[abs_r.size() / 2]);

      ceres::Problem::Options po;
      po.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
      po.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
      ceres::EigenQuaternionManifold quaternion_manifold;
      ceres::Problem problem(po);
      ceres::CauchyLoss loss(2.3849 * sigma);
      for (const auto& f : found) {
        for (const auto& c : f) {
          problem.AddResidualBlock(PointToPlaneResidual::Create(c), &loss, q[c.i].coeffs().data(), t[c.i].data(),
                                   q[c.j].coeffs().data(), t[c.j].data());
        }
      }
      for (std::size_t s = 0; s < n; ++s) {
        if (!problem.HasParameterBlock(q[s].coeffs().data())) continue;
        problem.SetManifold(q[s].coeffs().data(), &quaternion_manifold);
        if (s == options.anchor) {
          problem.SetParameterBlockConstant(q[s].coeffs().data());
          problem.SetParameterBlockConstant(t[s].data());
        }
      }
      ceres::Solver::Options so;
      so.linear_solver_type = ceres::DENSE_QR;
      so.max_num_iterations = 20;
      so.num_threads = omp_get_max_threads();
      so.function_tolerance = 1e-10;
      so.parameter_tolerance = 1e-10;
      ceres::Solver::Summary summary;
      ceres::Solve(so, &problem, &summary);
      double change = 0;
      for (std::size_t s = 0; s < n; ++s) {
        Rigid3 next = Rigid3::Identity();
        next.linear() = q[s].normalized().toRotationMatrix();
        next.translation() = t[s];
        change = std::max(change, (next.translation() - P[s].translation()).norm() +
                                      AngleDeg(next.linear() * P[s].linear().transpose()) * M_PI / 180.0 * 100.0);
        P[s] = next;
      }
      progress.Advance();
      if (change < 1e-4) break;
    }
    result.seconds_global = Since(t0);
  }

  // Back to the caller's world frame; corrections and overlap residuals.
  const Rigid3 T_world_centred = T_centred_world.inverse();
  result.T_world_sweep.resize(n);
  std::vector<Rigid3> P_world(n);
  for (std::size_t s = 0; s < n; ++s) {
    result.T_world_sweep[s] = T_world_centred * P[s];
    const Rigid3 correction = result.T_world_sweep[s] * start[s].inverse();
    result.correction_deg.push_back(AngleDeg(correction.linear()));
    const Eigen::Vector3d c = start[s] * sweeps[s].centroid;
    result.correction_mm.push_back((correction * c - c).norm());
  }
  std::vector<Rigid3> P_start(n);
  for (std::size_t s = 0; s < n; ++s) P_start[s] = T_centred_world * start[s];
  for (std::size_t k = 0; k < links.size(); ++k) {
    SweepPairReport pr;
    pr.i = links[k].i;
    pr.j = links[k].j;
    pr.overlap_fraction = links[k].overlap;
    pr.pairwise_success = pairwise_ok[k];
    pr.rms_before_mm = RmsPointToPlane(before[k], P_start);
    const auto after = FindCorrespondences(sweeps, P, pr.i, pr.j, options.global_points_per_pair, gate);
    pr.rms_after_mm = RmsPointToPlane(after, P);
    std::vector<double> d;
    for (const auto& c : after) d.push_back((P[c.j] * c.p - P[c.i] * c.q).norm());
    if (!d.empty()) {
      std::nth_element(d.begin(), d.begin() + static_cast<std::ptrdiff_t>(d.size() / 2), d.end());
      pr.median_after_mm = d[d.size() / 2];
    }
    result.pairs.push_back(pr);
  }

  // 5. One cloud: every sweep at its final pose, normals made consistent between sweeps.
  t0 = Clock::now();
  PointCloud merged;
  {
    std::vector<double> flip(n, 1.0);
    // The anchor's normals point away from the centroid of all points (outward for a closed object and
    // for a chest wall seen from the front); every other sweep agrees with the sweeps it overlaps.
    Eigen::Vector3d all_centroid = Eigen::Vector3d::Zero();
    for (std::size_t s = 0; s < n; ++s) all_centroid += P[s] * sweeps[s].centroid / static_cast<double>(n);
    auto vote = [&](std::size_t s, const std::function<Eigen::Vector3d(const Eigen::Vector3d&)>& reference) {
      double agree = 0;
      for (std::uint32_t r : sweeps[s].samples) {
        const Eigen::Vector3d p = P[s] * clouds[s].positions.row(r).transpose();
        const Eigen::Vector3d nn = P[s].linear() * sweeps[s].normals.row(r).transpose();
        const Eigen::Vector3d ref = reference(p);
        if (ref.squaredNorm() > 0) agree += nn.dot(ref) > 0 ? 1 : -1;
      }
      return agree;
    };
    flip[options.anchor] = vote(options.anchor, [&](const Eigen::Vector3d& p) { return Eigen::Vector3d(p - all_centroid); }) >= 0 ? 1.0 : -1.0;
    std::vector<bool> done(n, false);
    done[options.anchor] = true;
    for (std::size_t pass = 0; pass < n; ++pass) {
      for (const auto& l : links) {
        if (done[l.i] == done[l.j]) continue;
        const std::size_t from = done[l.i] ? l.i : l.j, to = done[l.i] ? l.j : l.i;
        const Rigid3 T_from_world = P[from].inverse();
        auto reference = [&](const Eigen::Vector3d& p) -> Eigen::Vector3d {
          std::uint32_t k;
          double d2;
          const Eigen::Vector3d local = T_from_world * p - sweeps[from].target->origin();
          if (!sweeps[from].target->tree().Nearest(local, &k, &d2) || d2 > gate * gate) return Eigen::Vector3d::Zero();
          return flip[from] * (P[from].linear() * sweeps[from].normals.row(k).transpose());
        };
        flip[to] = vote(to, reference) >= 0 ? 1.0 : -1.0;
        done[to] = true;
      }
    }
    for (std::size_t s = 0; s < n; ++s) {
      PointCloud c;
      c.positions = (clouds[s].positions * P[s].linear().transpose()).rowwise() + P[s].translation().transpose();
      c.normals = flip[s] * sweeps[s].normals * P[s].linear().transpose();
      if (clouds[s].has_colors()) c.colors = clouds[s].colors;
      c.scalars["sweep"] = Eigen::VectorXd::Constant(c.size(), static_cast<double>(s));
      merged.Append(c);
    }
  }

  // 6. Blend overlapping sweeps: move each point along its normal onto the locally weighted surface.
  if (options.smoothing_mm > 0) {
    KdTree3 tree(merged.positions);
    const double sigma2 = 0.25 * options.smoothing_mm * options.smoothing_mm;
    Points3 moved = merged.positions;
#pragma omp parallel
    {
      std::vector<std::pair<std::uint32_t, double>> nb;
#pragma omp for schedule(dynamic, 1024)
      for (Eigen::Index r = 0; r < merged.size(); ++r) {
        const Eigen::Vector3d p = merged.positions.row(r).transpose();
        const Eigen::Vector3d nr = merged.normals.row(r).transpose();
        if (nr.squaredNorm() < 0.5) continue;
        tree.Radius(p, options.smoothing_mm, &nb, false);
        double sw = 0, sd = 0;
        for (const auto& [k, d2] : nb) {
          const Eigen::Vector3d nk = merged.normals.row(k).transpose();
          if (nk.dot(nr) < 0.5) continue;  // the other side of a thin part
          const double w = std::exp(-d2 / (2.0 * sigma2));
          sw += w;
          sd += w * nr.dot(merged.positions.row(k).transpose() - p);
        }
        if (sw > 0) moved.row(r) = (p + nr * (sd / sw)).transpose();
      }
    }
    merged.positions.swap(moved);
  }
  result.seconds_blend = Since(t0);

  // 7. Statistical outlier removal, then decimation to the target spacing.
  t0 = Clock::now();
  std::vector<std::uint32_t> keep;
  if (options.outlier_neighbours > 0 && merged.size() > options.outlier_neighbours + 1) {
    KdTree3 tree(merged.positions);
    Eigen::VectorXd mean_d(merged.size());
#pragma omp parallel
    {
      std::vector<std::uint32_t> idx;
      std::vector<double> d2;
#pragma omp for schedule(static)
      for (Eigen::Index r = 0; r < merged.size(); ++r) {
        tree.Knn(merged.positions.row(r).transpose(), options.outlier_neighbours + 1, &idx, &d2);
        double s = 0;
        for (std::size_t k = 1; k < d2.size(); ++k) s += std::sqrt(d2[k]);
        mean_d(r) = s / static_cast<double>(std::max<std::size_t>(1, d2.size() - 1));
      }
    }
    const double mu = mean_d.mean();
    const double sd = std::sqrt((mean_d.array() - mu).square().mean());
    const double limit = mu + options.outlier_std_ratio * sd;
    for (Eigen::Index r = 0; r < merged.size(); ++r) {
      if (mean_d(r) <= limit) keep.push_back(static_cast<std::uint32_t>(r));
    }
  } else {
    keep.resize(static_cast<std::size_t>(merged.size()));
    std::iota(keep.begin(), keep.end(), 0u);
  }
  result.outliers_removed = merged.size() - static_cast<std::int64_t>(keep.size());
  if (options.target_spacing_mm > 0) keep = VoxelDownsample(merged.positions, options.target_spacing_mm, &keep);
  auto take = [&](const auto& m) {
    std::decay_t<decltype(m)> out(static_cast<Eigen::Index>(keep.size()), m.cols());
    for (std::size_t k = 0; k < keep.size(); ++k) out.row(static_cast<Eigen::Index>(k)) = m.row(keep[k]);
    return out;
  };
  result.merged.positions = take(merged.positions);
  result.merged.normals = take(merged.normals);
  if (merged.has_colors()) result.merged.colors = take(merged.colors);
  for (const auto& [name, v] : merged.scalars) {
    Eigen::VectorXd out(static_cast<Eigen::Index>(keep.size()));
    for (std::size_t k = 0; k < keep.size(); ++k) out(static_cast<Eigen::Index>(k)) = v(keep[k]);
    result.merged.scalars[name] = out;
  }
  result.points_out = result.merged.size();
  result.seconds_filter = Since(t0);
  // Back to the caller's world frame.
  result.merged.positions.rowwise() += T_world_centred.translation().transpose();

  double worst_after = 0;
  for (const auto& pr : result.pairs) worst_after = std::max(worst_after, pr.rms_after_mm);
  result.message = std::to_string(n) + " sweeps, " + std::to_string(links.size()) + " overlapping pairs, worst pair RMS " +
                   std::to_string(worst_after).substr(0, 5) + " mm, " + std::to_string(result.points_out) + " points out";
  return result;
}

}  // namespace pectus
