#include "registration/generalised_procrustes.h"

#include <algorithm>
#include <cmath>
#include <set>

#include "registration/landmark_alignment.h"
#include "shape/core/error.h"

namespace pectus {
namespace {

std::string NameOf(const std::vector<std::string>& names, std::size_t i) {
  return i < names.size() ? names[i] : "shape " + std::to_string(i + 1);
}

}  // namespace

bool ProcrustesOptions::IsValid(std::string* why) const {
  auto fail = [&](const char* text) {
    if (why) *why = text;
    return false;
  };
  if (reference && *reference < 0) return fail("reference must be >= 0");
  if (max_iterations < 0) return fail("max_iterations must be >= 0");
  if (!(tolerance_mm >= 0.0)) return fail("tolerance_mm must be >= 0");
  if (!(min_spread_ratio >= 0.0 && min_spread_ratio < 1.0)) return fail("min_spread_ratio must be in [0, 1)");
  return true;
}

ProcrustesResult GeneralisedProcrustes(const std::vector<Points3>& X, const ProcrustesOptions& options,
                                       const std::vector<std::string>& names) {
  std::string why;
  if (!options.IsValid(&why)) ThrowUsage("Procrustes: " + why);
  if (X.size() < 2) ThrowBadInput("Procrustes", "needs at least two shapes");
  if (options.reference && static_cast<std::size_t>(*options.reference) >= X.size())
    ThrowUsage("Procrustes: reference index out of range");
  for (std::size_t i = 1; i < X.size(); ++i) {
    if (X[i].rows() != X[0].rows()) {
      ThrowBadInput(NameOf(names, i), "has " + std::to_string(X[i].rows()) + " points where " +
                                          NameOf(names, 0) + " has " + std::to_string(X[0].rows()));
    }
  }
  const auto n = static_cast<double>(X.size());
  const Eigen::VectorXd no_weights;
  auto align = [&](std::size_t i, const Points3& target) {
    return UmeyamaAlignment(X[i], target, no_weights, options.estimate_scale, options.min_spread_ratio,
                            NameOf(names, i));
  };

  ProcrustesResult result;
  result.T_mean_shape.resize(X.size());
  Points3 mean = Points3::Zero(X[0].rows(), 3);
  if (options.reference) {
    mean = X[static_cast<std::size_t>(*options.reference)];
  } else {
    for (const Points3& x : X) mean += x;
    mean /= n;
  }
  for (int it = 1; it <= options.max_iterations && !result.converged; ++it) {
    // Align every shape to the current mean, average.
    Points3 next = Points3::Zero(mean.rows(), 3);
    for (std::size_t i = 0; i < X.size(); ++i) {
      result.T_mean_shape[i] = align(i, mean);
      next += result.T_mean_shape[i].Apply(X[i]);
    }
    next /= n;
    // Fix the gauge: the mean in the reference's frame and, with scale, of the reference's size.
    if (options.reference) {
      next = UmeyamaAlignment(next, X[static_cast<std::size_t>(*options.reference)], no_weights,
                              options.estimate_scale, options.min_spread_ratio, "mean shape")
                 .Apply(next);
    }
    const double moved = (next - mean).rowwise().norm().maxCoeff();
    mean = std::move(next);
    result.iterations = it;
    result.converged = moved < options.tolerance_mm;
  }
  double sum = 0.0;
  for (std::size_t i = 0; i < X.size(); ++i) {
    result.T_mean_shape[i] = align(i, mean);
    sum += (result.T_mean_shape[i].Apply(X[i]) - mean).squaredNorm();
  }
  result.rms_mm = std::sqrt(sum / (n * static_cast<double>(mean.rows())));
  result.mean_points = std::move(mean);
  return result;
}

LandmarkProcrustesResult GeneralisedProcrustes(const std::vector<LandmarkSet>& shapes,
                                               const ProcrustesOptions& options,
                                               const std::vector<std::string>& names) {
  std::string why;
  if (!options.IsValid(&why)) ThrowUsage("Procrustes: " + why);
  if (shapes.size() < 2) ThrowBadInput("Procrustes", "needs at least two landmark sets");
  const auto ref = static_cast<std::size_t>(options.reference.value_or(0));
  if (ref >= shapes.size()) ThrowUsage("Procrustes: reference index out of range");
  auto name = [&](std::size_t i) {
    return i < names.size() ? names[i] : "landmark set " + std::to_string(i + 1);
  };
  for (std::size_t i = 0; i < shapes.size(); ++i) shapes[i].Validate(name(i));

  // Labels present in every set, in the reference's order.
  std::vector<std::string> labels;
  std::set<std::string> skipped;
  for (const Landmark& l : shapes[ref].items) {
    bool everywhere = true;
    for (const LandmarkSet& s : shapes) everywhere = everywhere && s.Find(l.label) != nullptr;
    if (everywhere) {
      labels.push_back(l.label);
    } else {
      skipped.insert(l.label);
    }
  }
  for (const LandmarkSet& s : shapes) {
    for (const Landmark& l : s.items) {
      if (std::find(labels.begin(), labels.end(), l.label) == labels.end()) skipped.insert(l.label);
    }
  }
  if (labels.size() < 3) {
    ThrowBadInput("Procrustes", "only " + std::to_string(labels.size()) +
                                    " landmark labels are present in every set; need at least 3");
  }
  const auto L = static_cast<Eigen::Index>(labels.size());
  std::vector<Points3> X(shapes.size(), Points3(L, 3));
  std::vector<std::string> set_names;
  for (std::size_t i = 0; i < shapes.size(); ++i) {
    set_names.push_back(name(i));
    for (Eigen::Index k = 0; k < L; ++k) {
      X[i].row(k) = shapes[i].Find(labels[static_cast<std::size_t>(k)])->position.transpose();
    }
  }
  LandmarkProcrustesResult result;
  static_cast<ProcrustesResult&>(result) = GeneralisedProcrustes(X, options, set_names);
  result.skipped.assign(skipped.begin(), skipped.end());
  for (Eigen::Index k = 0; k < L; ++k) {
    result.mean.items.push_back(
        {labels[static_cast<std::size_t>(k)], result.mean_points.row(k).transpose(), ""});
  }
  return result;
}

}  // namespace pectus
