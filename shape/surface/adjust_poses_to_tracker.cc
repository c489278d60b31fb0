#include "shape/surface/adjust_poses_to_tracker.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>
#include <utility>

#include "registration/robust_loss.h"
#include "shape/core/error.h"

namespace pectus {
namespace {

using Vector6 = Eigen::Matrix<double, 6, 1>;
using Matrix6 = Eigen::Matrix<double, 6, 6>;

Eigen::Matrix3d Skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d s;
  s << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return s;
}

// A twist (w, v) about the origin, as a twist about c: the motion of c is v + w x c = v - [c]x w.
Matrix6 TwistAbout(const Eigen::Vector3d& c) {
  Matrix6 m = Matrix6::Identity();
  m.block<3, 3>(3, 0) = -Skew(c);
  return m;
}

// Sum of the weighted normal equations of one pair's residuals, and the same for the noise of the normals.
struct PairSums {
  Matrix6 H = Matrix6::Zero(), spurious = Matrix6::Zero();
  Vector6 g = Vector6::Zero();
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  double weight = 0.0;
  int count = 0;
  // Every use of a point (sweep << 32 | row) with its correspondence's weight; the sum of 2 w^2 over the
  // correspondences, and of w^2 over the uses of points whose row is not known (each its own point).
  std::vector<std::pair<std::uint64_t, double>> uses;
  double independent_w2 = 0.0, unknown_w2 = 0.0;
};

// The factor sum_k 2 w_k^2 / sum_points (sum of w over its uses)^2 on a pair's information: the variance
// of the gradient, whose terms of one point add up (same sign on the relative pose), over the variance
// the information assumes (every point in one residual), for the residuals' local Jacobians alike.
double IndependentFraction(PairSums* ps) {
  if (!(ps->independent_w2 > 0.0)) return 1.0;
  std::sort(ps->uses.begin(), ps->uses.end());
  double shared = ps->unknown_w2;
  for (std::size_t a = 0; a < ps->uses.size();) {
    double w = 0.0;
    std::size_t b = a;
    for (; b < ps->uses.size() && ps->uses[b].first == ps->uses[a].first; ++b) w += ps->uses[b].second;
    shared += w * w;
    a = b;
  }
  return std::clamp(ps->independent_w2 / std::max(shared, 1e-300), 0.0, 1.0);
}

}  // namespace

bool TrackerAdjustmentOptions::IsValid(std::string* why) const {
  auto fail = [&](const char* text) {
    if (why) *why = text;
    return false;
  };
  if (!(min_robust_scale_mm > 0.0) || !std::isfinite(min_robust_scale_mm))
    return fail("robust scale floor must be > 0");
  if (!(min_pinned_ratio >= 1.0) || !std::isfinite(min_pinned_ratio))
    return fail("pinned ratio must be >= 1");
  return true;
}

TrackerAdjustmentResult AdjustPosesToTracker(const std::vector<SweepCorrespondence>& correspondences,
                                             const std::vector<SweepSurface>& sweeps, const PosePrior& prior,
                                             std::vector<Rigid3>* T_world_sweep,
                                             const TrackerAdjustmentOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) ThrowUsage("tracker adjustment: " + why);
  std::vector<Rigid3>& P = *T_world_sweep;
  const std::size_t n = P.size();
  if (sweeps.size() != n || prior.T_world_sweep.size() != n || prior.centre.size() != n ||
      !(prior.rotation_sd_deg > 0.0) || !(prior.translation_sd_mm > 0.0)) {
    ThrowUsage("tracker adjustment: a sweep, a prior pose and a centre per pose, and positive accuracies");
  }
  for (const auto& c : correspondences) {
    if (c.i >= n || c.j >= n || c.i == c.j)
      ThrowUsage("tracker adjustment: correspondence between invalid sweeps");
  }
  TrackerAdjustmentResult result;

  // 1. Residuals at the current poses and their robust scale.
  std::vector<double> r(correspondences.size()), abs_r(correspondences.size());
  double sum2 = 0.0;
  for (std::size_t k = 0; k < correspondences.size(); ++k) {
    const SweepCorrespondence& c = correspondences[k];
    r[k] = (P[c.i].linear() * c.n).dot(P[c.j] * c.p - P[c.i] * c.q);
    abs_r[k] = std::abs(r[k]);
    sum2 += r[k] * r[k];
  }
  result.rms_before_mm = correspondences.empty() ? 0.0 : std::sqrt(sum2 / double(correspondences.size()));
  const double s = std::max(options.min_robust_scale_mm, correspondences.empty() ? 0.0 : MadScale(&abs_r));
  result.robust_scale_mm = s;
  const double c_loss = RobustTuningConstant(RobustLoss::kCauchy) * s;
  // The angular noise of the target's normals, as its sweep measured it (SweepSurface::normal_variance).
  auto normal_variance = [&](std::size_t sweep) { return sweeps[sweep].normal_variance; };

  // 2. Every pair's residuals as one 6 x 6 constraint on its relative twist (hi relative to lo), about the
  // overlap's centre.
  std::map<std::pair<std::size_t, std::size_t>, PairSums> sums;
  for (const auto& c : correspondences) {
    auto& ps = sums[{std::min(c.i, c.j), std::max(c.i, c.j)}];
    ps.centre += P[c.j] * c.p;
    ps.weight += 1.0;
  }
  for (auto& [key, ps] : sums) ps.centre /= ps.weight;
  for (std::size_t k = 0; k < correspondences.size(); ++k) {
    const SweepCorrespondence& c = correspondences[k];
    auto& ps = sums[{std::min(c.i, c.j), std::max(c.i, c.j)}];
    const Eigen::Vector3d normal = P[c.i].linear() * c.n;
    const Eigen::Vector3d arm = P[c.j] * c.p - ps.centre;
    const double sign = c.j > c.i ? 1.0 : -1.0;  // the source sweep is hi: + its twist
    Vector6 J;
    J << arm.cross(normal), normal;
    J *= sign;
    const double robust = RobustWeight(RobustLoss::kCauchy, r[k], c_loss) * c.weight;
    const double w = robust / (s * s);
    if (options.count_shared_points) {
      ps.independent_w2 += 2.0 * robust * robust;
      for (const auto& [sweep, row] : {std::pair{c.j, c.p_row}, std::pair{c.i, c.q_row}}) {
        if (row == kUnknownRow)
          ps.unknown_w2 += robust * robust;
        else
          ps.uses.push_back({std::uint64_t(sweep) << 32 | row, robust});
      }
    }
    ps.H += w * J * J.transpose();
    ps.g += w * r[k] * J;
    const double e2 = normal_variance(c.i);
    const Eigen::Vector3d t1 = normal.unitOrthogonal(), t2 = normal.cross(t1);
    for (const Eigen::Vector3d& t : {t1, t2}) {
      Vector6 Jt;
      Jt << arm.cross(t), t;
      ps.spurious += w * e2 * Jt * Jt.transpose();
    }
    ++ps.count;
  }

  // 3. The joint normal equations: every pair's pinned part, every sweep's prior.
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(Eigen::Index(6 * n), Eigen::Index(6 * n));
  Eigen::VectorXd b = Eigen::VectorXd::Zero(Eigen::Index(6 * n));
  for (auto& [key, ps] : sums) {
    const auto [lo, hi] = key;
    PairConstraintReport report{lo, hi, 0, ps.count};
    // A point's noise once, however many of the pair's residuals carry it: the pair's information (and
    // the normals' share of it, so lambda is unchanged) scaled down; its own best step is the same.
    report.independent_fraction = IndependentFraction(&ps);
    ps.H *= report.independent_fraction;
    ps.g *= report.independent_fraction;
    ps.spurious *= report.independent_fraction;
    const double scale = std::max(ps.spurious.trace(), ps.H.trace()) * 1e-12 + 1e-300;
    const Matrix6 B = ps.spurious + scale * Matrix6::Identity();
    Eigen::GeneralizedSelfAdjointEigenSolver<Matrix6> ges(ps.H, B);
    if (ges.info() != Eigen::Success) continue;
    Matrix6 Hp = Matrix6::Zero();
    Vector6 step = Vector6::Zero();
    for (int d = 0; d < 6; ++d) {
      const double lambda = ges.eigenvalues()(d);
      if (!(lambda >= options.min_pinned_ratio)) continue;
      const Vector6 u = ges.eigenvectors().col(d);  // u' B u = 1, u' H u = lambda
      const Vector6 Bu = B * u;
      // The normals' noise alone puts lambda = 1 along any direction: keep what the overlap adds to it.
      Hp += (lambda - 1.0) * Bu * Bu.transpose();
      step -= u * (u.dot(ps.g) / lambda);
      ++report.pinned_directions;
    }
    result.pairs.push_back(report);
    const Matrix6 M = TwistAbout(ps.centre);
    const Matrix6 K = M.transpose() * Hp * M;
    const Vector6 kb = M.transpose() * Hp * step;
    const Eigen::Index a = Eigen::Index(6 * lo), z = Eigen::Index(6 * hi);
    A.block<6, 6>(a, a) += K;
    A.block<6, 6>(z, z) += K;
    A.block<6, 6>(a, z) -= K;
    A.block<6, 6>(z, a) -= K;
    b.segment<6>(z) += kb;
    b.segment<6>(a) -= kb;
  }
  const double wr = 1.0 / std::pow(prior.rotation_sd_deg * M_PI / 180.0, 2);
  const double wt = 1.0 / std::pow(prior.translation_sd_mm, 2);
  Vector6 W;
  W << wr, wr, wr, wt, wt, wt;
  for (std::size_t sw = 0; sw < n; ++sw) {
    const Rigid3& T0 = prior.T_world_sweep[sw];
    const Eigen::AngleAxisd turned(P[sw].linear() * T0.linear().transpose());
    Vector6 e;
    e << turned.angle() * turned.axis(), P[sw] * prior.centre[sw] - T0 * prior.centre[sw];
    const Matrix6 M = TwistAbout(P[sw] * prior.centre[sw]);
    const Eigen::Index a = Eigen::Index(6 * sw);
    A.block<6, 6>(a, a) += M.transpose() * W.asDiagonal() * M;
    b.segment<6>(a) -= M.transpose() * W.asDiagonal() * e;
  }

  // 4. Solve and move every sweep by its twist.
  const Eigen::VectorXd xi = A.ldlt().solve(b);
  result.information = A;
  for (std::size_t sw = 0; sw < n; ++sw) {
    const Eigen::Vector3d w = xi.segment<3>(Eigen::Index(6 * sw));
    const Eigen::Vector3d v = xi.segment<3>(Eigen::Index(6 * sw + 3));
    if (!w.allFinite() || !v.allFinite()) continue;
    Rigid3 step = Rigid3::Identity();
    if (w.norm() > 0.0) step.linear() = Eigen::AngleAxisd(w.norm(), w.normalized()).toRotationMatrix();
    step.translation() = v;
    P[sw] = step * P[sw];
  }
  return result;
}

}  // namespace pectus
