#include "registration/generalised_procrustes.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <set>

#include "registration/landmark_alignment.h"
#include "shape/core/error.h"
#include "shape/core/task_runner.h"

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
                                       const std::vector<std::string>& names, TaskRunner* runner) {
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
  SerialTaskRunner serial;
  TaskRunner& farm = runner != nullptr ? *runner : serial;
  // The shapes in blocks fixed by their number: each block's part of a sum is computed on one process, and
  // every process adds the parts in block order, so the bits do not depend on the processes.
  const auto count = static_cast<std::int64_t>(X.size());
  const std::int64_t per_block = BlockRows(count, 32);
  const std::int64_t blocks = (count + per_block - 1) / per_block;
  const Eigen::Index p = X[0].rows();
  auto sum_of = [&](const std::function<Points3(std::size_t)>& term) {
    std::vector<double> parts(static_cast<std::size_t>(blocks * 3 * p));
    farm.ComputeBlocks(
        BlockOffsets(blocks, 1, 3 * p),
        [&](int b, double* out) {
          Eigen::Map<Points3> part(out, p, 3);
          part.setZero();
          const std::int64_t end = std::min(count, (b + 1) * per_block);
          for (std::int64_t i = b * per_block; i < end; ++i) part += term(static_cast<std::size_t>(i));
        },
        parts.data());
    Points3 sum = Points3::Zero(p, 3);
    for (std::int64_t b = 0; b < blocks; ++b)
      sum += Eigen::Map<const Points3>(parts.data() + b * 3 * p, p, 3);
    return sum;
  };

  ProcrustesResult result;
  result.T_mean_shape.resize(X.size());
  Points3 mean = options.reference ? X[static_cast<std::size_t>(*options.reference)]
                                   : Points3(sum_of([&](std::size_t i) { return X[i]; }) / n);
  for (int it = 1; it <= options.max_iterations && !result.converged; ++it) {
    // Align every shape to the current mean, average.
    Points3 next = sum_of([&](std::size_t i) { return align(i, mean).Apply(X[i]); }) / n;
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
  // Every shape aligned to the last mean: per shape its transform (scale, rotation, translation) and its
  // squared distance to the mean.
  constexpr int kWidth = 14;
  std::vector<double> last(static_cast<std::size_t>(count * kWidth));
  farm.ComputeBlocks(
      BlockOffsets(count, per_block, kWidth),
      [&](int b, double* out) {
        const std::int64_t end = std::min(count, (b + 1) * per_block);
        for (std::int64_t i = b * per_block; i < end; ++i, out += kWidth) {
          const Similarity3 T = align(static_cast<std::size_t>(i), mean);
          out[0] = T.scale;
          Eigen::Map<Eigen::Matrix3d>(out + 1) = T.rotation;
          Eigen::Map<Eigen::Vector3d>(out + 10) = T.translation;
          out[13] = (T.Apply(X[static_cast<std::size_t>(i)]) - mean).squaredNorm();
        }
      },
      last.data());
  double sum = 0.0;
  for (std::int64_t i = 0; i < count; ++i) {
    const double* row = last.data() + i * kWidth;
    Similarity3& T = result.T_mean_shape[static_cast<std::size_t>(i)];
    T.scale = row[0];
    T.rotation = Eigen::Map<const Eigen::Matrix3d>(row + 1);
    T.translation = Eigen::Map<const Eigen::Vector3d>(row + 10);
    sum += row[13];
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
