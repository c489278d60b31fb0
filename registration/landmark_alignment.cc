#include "registration/landmark_alignment.h"

#include <Eigen/Eigenvalues>
#include <Eigen/SVD>
#include <cmath>
#include <sstream>

#include "shape/core/error.h"

namespace pectus {
namespace {

// Weighted mean and scatter (divided by the total weight) of the rows of `points`.
void WeightedMoments(const Points3& points, const Eigen::VectorXd& w, double total, Eigen::Vector3d* mean,
                     Eigen::Matrix3d* scatter) {
  *mean = (points.transpose() * w) / total;
  scatter->setZero();
  for (Eigen::Index i = 0; i < points.rows(); ++i) {
    const Eigen::Vector3d d = points.row(i).transpose() - *mean;
    *scatter += w(i) * d * d.transpose();
  }
  *scatter /= total;
}

// Throws if the weighted points hug a line: the spread across the best line is below `ratio` times the
// spread along it.
void CheckNotCollinear(const Eigen::Matrix3d& scatter, double ratio, const std::string& what) {
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(scatter);
  const Eigen::Vector3d sd = eig.eigenvalues().cwiseMax(0.0).cwiseSqrt();  // ascending
  if (!(sd(2) > 0.0)) ThrowBadInput(what, "all landmarks are at the same position");
  if (sd(1) < ratio * sd(2)) {
    std::ostringstream msg;
    msg.precision(3);
    msg << "landmarks are (nearly) collinear: spread across their line " << sd(1) << " mm against " << sd(2)
        << " mm along it (need a ratio of at least " << ratio
        << "); the rotation about that line is undetermined. Add a landmark off the line";
    ThrowBadInput(what, msg.str());
  }
}

}  // namespace

bool LandmarkAlignmentOptions::IsValid(std::string* why) const {
  if (!(min_spread_ratio >= 0.0 && min_spread_ratio < 1.0)) {
    if (why) *why = "min_spread_ratio must be in [0, 1)";
    return false;
  }
  for (const auto& [label, w] : weights) {
    if (!std::isfinite(w) || w < 0.0) {
      if (why) *why = "weight of landmark '" + label + "' must be finite and >= 0";
      return false;
    }
  }
  return true;
}

Similarity3 UmeyamaAlignment(const Points3& source, const Points3& target, const Eigen::VectorXd& weights,
                             bool estimate_scale, double min_spread_ratio, const std::string& what) {
  const Eigen::Index n = source.rows();
  if (target.rows() != n) {
    ThrowBadInput(what, "source and target have different numbers of points (" + std::to_string(n) + " and " +
                            std::to_string(target.rows()) + ")");
  }
  if (weights.size() != 0 && weights.size() != n) {
    ThrowBadInput(what, "expected " + std::to_string(n) + " weights, got " + std::to_string(weights.size()));
  }
  if (!source.allFinite() || !target.allFinite()) ThrowBadInput(what, "a coordinate is not finite");
  const Eigen::VectorXd w = weights.size() == 0 ? Eigen::VectorXd::Ones(n) : weights;
  if (!w.allFinite() || (w.array() < 0.0).any()) ThrowBadInput(what, "weights must be finite and >= 0");
  const Eigen::Index used = (w.array() > 0.0).count();
  if (used < 3) {
    ThrowBadInput(
        what, "need at least 3 corresponding landmarks (with positive weight), got " + std::to_string(used));
  }
  const double total = w.sum();

  // Eqs. (34)-(36), (38): weighted means, source variance, cross-covariance. The scatter matrices are
  // about the means, so a far-away common offset cancels before any product is formed.
  Eigen::Vector3d mu_x, mu_y;
  Eigen::Matrix3d scatter_x, scatter_y;
  WeightedMoments(source, w, total, &mu_x, &scatter_x);
  WeightedMoments(target, w, total, &mu_y, &scatter_y);
  CheckNotCollinear(scatter_x, min_spread_ratio, what + " (source)");
  CheckNotCollinear(scatter_y, min_spread_ratio, what + " (target)");
  const double sigma2_x = scatter_x.trace();
  Eigen::Matrix3d sigma_xy = Eigen::Matrix3d::Zero();
  for (Eigen::Index i = 0; i < n; ++i) {
    sigma_xy += w(i) * (target.row(i).transpose() - mu_y) * (source.row(i).transpose() - mu_x).transpose();
  }
  sigma_xy /= total;

  // Eqs. (39), (43): S = diag(1, 1, -1) when a reflection would fit better. det(U) det(V) is used
  // instead of det(Sigma_xy) so that rank-2 cross-covariances (three landmarks) are handled (Eq. 43).
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(sigma_xy, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Vector3d s_diag = Eigen::Vector3d::Ones();
  if (svd.matrixU().determinant() * svd.matrixV().determinant() < 0.0) s_diag(2) = -1.0;

  Similarity3 T;
  T.rotation = svd.matrixU() * s_diag.asDiagonal() * svd.matrixV().transpose();  // Eq. (40)
  T.scale = estimate_scale ? svd.singularValues().dot(s_diag) / sigma2_x : 1.0;  // Eq. (42)
  if (!(T.scale > 0.0) || !std::isfinite(T.scale)) {
    ThrowBadInput(what, "the landmarks give a non-positive scale; are the labels swapped?");
  }
  T.translation = mu_y - T.scale * T.rotation * mu_x;  // Eq. (41)
  return T;
}

LandmarkAlignmentResult AlignLandmarks(const LandmarkSet& source, const LandmarkSet& target,
                                       const LandmarkAlignmentOptions& options,
                                       const std::string& source_name, const std::string& target_name) {
  std::string why;
  if (!options.IsValid(&why)) ThrowUsage("landmark alignment: " + why);
  source.Validate(source_name);
  target.Validate(target_name);

  LandmarkAlignmentResult result;
  std::vector<Eigen::Vector3d> xs, ys;
  std::vector<double> ws;
  for (const Landmark& l : source.items) {
    const Landmark* match = target.Find(l.label);
    if (match == nullptr) {
      result.unmatched.push_back(l.label);
      continue;
    }
    result.labels.push_back(l.label);
    xs.push_back(l.position);
    ys.push_back(match->position);
    const auto it = options.weights.find(l.label);
    ws.push_back(it == options.weights.end() ? 1.0 : it->second);
  }
  for (const Landmark& l : target.items) {
    if (source.Find(l.label) == nullptr) result.unmatched.push_back(l.label);
  }

  const std::string pair_name = source_name + " -> " + target_name;
  auto list = [](const std::vector<std::string>& labels) {
    std::string s;
    for (const auto& l : labels) s += (s.empty() ? "'" : ", '") + l + "'";
    return s.empty() ? std::string("none") : s;
  };
  if (options.require_all_labels && !result.unmatched.empty()) {
    ThrowBadInput(pair_name,
                  "landmark labels do not match; found in only one set: " + list(result.unmatched));
  }
  if (result.labels.size() < 3) {
    ThrowBadInput(pair_name, "need at least 3 landmarks with the same label in both sets, found " +
                                 std::to_string(result.labels.size()) + " (" + list(result.labels) +
                                 "); labels found in only one set: " + list(result.unmatched));
  }

  const auto n = static_cast<Eigen::Index>(xs.size());
  Points3 x(n, 3), y(n, 3);
  Eigen::VectorXd w(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    x.row(i) = xs[static_cast<std::size_t>(i)].transpose();
    y.row(i) = ys[static_cast<std::size_t>(i)].transpose();
    w(i) = ws[static_cast<std::size_t>(i)];
  }
  result.T_target_source =
      UmeyamaAlignment(x, y, w, options.estimate_scale, options.min_spread_ratio, pair_name);

  result.residuals_mm.resize(n);
  double sum = 0.0;
  Eigen::Index worst = 0;
  for (Eigen::Index i = 0; i < n; ++i) {
    result.residuals_mm(i) = (result.T_target_source * Eigen::Vector3d(x.row(i).transpose()) -
                              Eigen::Vector3d(y.row(i).transpose()))
                                 .norm();
    sum += w(i) * result.residuals_mm(i) * result.residuals_mm(i);
    if (result.residuals_mm(i) > result.residuals_mm(worst)) worst = i;
  }
  result.rms_mm = std::sqrt(sum / w.sum());
  std::ostringstream msg;
  msg.precision(3);
  msg << n << " landmarks, RMS " << result.rms_mm << " mm, largest " << result.residuals_mm(worst) << " mm ('"
      << result.labels[static_cast<std::size_t>(worst)] << "')";
  if (!result.unmatched.empty()) msg << "; skipped (in one set only): " << list(result.unmatched);
  result.message = msg.str();
  return result;
}

}  // namespace pectus
