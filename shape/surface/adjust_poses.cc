#include "shape/surface/adjust_poses.h"

#include <ceres/ceres.h>
#include <omp.h>

#include <algorithm>
#include <cmath>

#include "registration/robust_loss.h"
#include "shape/core/error.h"

namespace pectus {
namespace {

// (R_i n) . (R_j p + t_j - R_i q - t_i), poses as (unit quaternion x, y, z, w; translation).
struct PointToPlaneResidual {
  PointToPlaneResidual(const Eigen::Vector3d& p, const Eigen::Vector3d& q, const Eigen::Vector3d& n, double w)
      : p_(p), q_(q), n_(n), sqrt_w_(std::sqrt(w)) {}
  template <typename T>
  bool operator()(const T* qi, const T* ti, const T* qj, const T* tj, T* residual) const {
    using Quat = Eigen::Quaternion<T>;
    using Vec = Eigen::Matrix<T, 3, 1>;
    const Eigen::Map<const Quat> Ri(qi), Rj(qj);
    const Eigen::Map<const Vec> Ti(ti), Tj(tj);
    const Vec world_p = Rj * p_.cast<T>() + Tj;
    const Vec world_q = Ri * q_.cast<T>() + Ti;
    residual[0] = sqrt_w_ * (Ri * n_.cast<T>()).dot(world_p - world_q);
    return true;
  }
  Eigen::Vector3d p_, q_, n_;
  double sqrt_w_;
};

}  // namespace

bool PoseAdjustmentOptions::IsValid(std::string* why) const {
  auto fail = [&](const char* text) {
    if (why) *why = text;
    return false;
  };
  if (!(min_robust_scale_mm > 0.0) || !std::isfinite(min_robust_scale_mm))
    return fail("robust scale floor must be > 0");
  if (max_iterations < 1) return fail("max iterations must be >= 1");
  return true;
}

PoseAdjustmentResult AdjustPoses(const std::vector<SweepCorrespondence>& pairs,
                                 std::vector<Rigid3>* T_world_sweep, const PoseAdjustmentOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) ThrowUsage("pose adjustment: " + why);
  std::vector<Rigid3>& P = *T_world_sweep;
  const std::size_t n = P.size();
  if (options.anchor >= n)
    ThrowUsage("pose adjustment: anchor " + std::to_string(options.anchor) + " of " + std::to_string(n));
  for (const auto& c : pairs) {
    if (c.i >= n || c.j >= n || c.i == c.j)
      ThrowUsage("pose adjustment: correspondence between invalid sweeps");
  }
  PoseAdjustmentResult result;
  result.rms_before_mm = PointToPlaneRms(pairs, P);
  if (pairs.empty()) {
    result.converged = true;
    result.message = "no correspondences";
    return result;
  }
  // Robust scale from the starting residuals.
  std::vector<double> abs_r;
  abs_r.reserve(pairs.size());
  for (const auto& c : pairs)
    abs_r.push_back(std::abs((P[c.i].linear() * c.n).dot(P[c.j] * c.p - P[c.i] * c.q)));
  result.robust_scale_mm = std::max(options.min_robust_scale_mm, MadScale(&abs_r));

  std::vector<Eigen::Quaterniond> q(n);
  std::vector<Eigen::Vector3d> t(n);
  for (std::size_t s = 0; s < n; ++s) {
    q[s] = Eigen::Quaterniond(P[s].linear()).normalized();
    t[s] = P[s].translation();
  }
  ceres::Problem::Options po;
  po.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  po.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::EigenQuaternionManifold quaternion_manifold;
  ceres::CauchyLoss loss(RobustTuningConstant(RobustLoss::kCauchy) * result.robust_scale_mm);
  ceres::Problem problem(po);
  for (const auto& c : pairs) {
    problem.AddResidualBlock(new ceres::AutoDiffCostFunction<PointToPlaneResidual, 1, 4, 3, 4, 3>(
                                 new PointToPlaneResidual(c.p, c.q, c.n, c.weight)),
                             &loss, q[c.i].coeffs().data(), t[c.i].data(), q[c.j].coeffs().data(),
                             t[c.j].data());
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
  so.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
  so.max_num_iterations = options.max_iterations;
  so.num_threads = omp_get_max_threads();
  so.function_tolerance = 1e-10;
  so.parameter_tolerance = 1e-10;
  so.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  ceres::Solve(so, &problem, &summary);
  for (std::size_t s = 0; s < n; ++s) {
    P[s].linear() = q[s].normalized().toRotationMatrix();
    P[s].translation() = t[s];
  }
  result.rms_after_mm = PointToPlaneRms(pairs, P);
  result.iterations = int(summary.iterations.size());
  result.converged = summary.termination_type == ceres::CONVERGENCE;
  result.message = summary.BriefReport();
  return result;
}

}  // namespace pectus
