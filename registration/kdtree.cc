// pectus: k-d tree over 3D points (registration/kdtree.h): building it, whole or as two halves side by side.
#include "registration/kdtree.h"

#include <algorithm>
#include <vector>

namespace pectus {

KdTree3::KdTree3(const Points3& points, int leaf_size, bool halves) : points_(&points) {
  const Eigen::Index n = points.rows();
  if (!halves || n < 2 * kMinHalfPoints) {
    parts_.push_back(std::make_unique<Part>(&points, 0, n, leaf_size));
    return;
  }
  // The cut: the median along the axis of widest extent.
  const Eigen::RowVector3d extent = points.colwise().maxCoeff() - points.colwise().minCoeff();
  extent.maxCoeff(&axis_);
  std::vector<double> along(static_cast<std::size_t>(n));
  for (Eigen::Index i = 0; i < n; ++i) along[static_cast<std::size_t>(i)] = points(i, axis_);
  const auto middle = along.begin() + n / 2;
  std::nth_element(along.begin(), middle, along.end());
  cut_ = *middle;
  // The halves: the rows below the cut and the rest, each in row order (neighbouring rows, a scanner's
  // neighbours, stay near each other in memory).
  rows_.reserve(static_cast<std::size_t>(n));
  for (Eigen::Index i = 0; i < n; ++i)
    if (points(i, axis_) < cut_) rows_.push_back(static_cast<std::uint32_t>(i));
  const auto below = static_cast<Eigen::Index>(rows_.size());
  for (Eigen::Index i = 0; i < n; ++i)
    if (!(points(i, axis_) < cut_)) rows_.push_back(static_cast<std::uint32_t>(i));
  ordered_ = std::make_unique<Points3>(n, 3);
  for (Eigen::Index i = 0; i < n; ++i) ordered_->row(i) = points.row(rows_[static_cast<std::size_t>(i)]);
  parts_.push_back(std::make_unique<Part>(ordered_.get(), 0, below, leaf_size, false));
  parts_.push_back(std::make_unique<Part>(ordered_.get(), below, n - below, leaf_size, false));
#pragma omp parallel for num_threads(2) schedule(dynamic, 1)
  for (int k = 0; k < 2; ++k) {
    Part& part = *parts_[static_cast<std::size_t>(k)];
    if (part.adaptor.count > 0) part.index->buildIndex();  // none below the cut: every point alike
  }
}

KdTree3::~KdTree3() = default;
KdTree3::KdTree3(KdTree3&&) noexcept = default;
KdTree3& KdTree3::operator=(KdTree3&&) noexcept = default;

}  // namespace pectus
