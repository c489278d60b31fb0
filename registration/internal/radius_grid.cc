// pectus: a uniform grid for the k nearest points within a radius (registration/internal/radius_grid.h).
#include "registration/internal/radius_grid.h"

#include <algorithm>
#include <cmath>

namespace pectus::icp_detail {

std::optional<RadiusGrid> RadiusGrid::Build(const Points3& points, double cell, std::size_t max_cells) {
  if (!(cell > 0.0) || !std::isfinite(cell) || points.rows() == 0) return std::nullopt;
  const Eigen::Vector3d low = points.colwise().minCoeff().transpose();
  const Eigen::Vector3d high = points.colwise().maxCoeff().transpose();
  if (!low.allFinite() || !high.allFinite()) return std::nullopt;
  RadiusGrid g;
  g.cell_ = cell;
  g.inverse_cell_ = 1.0 / cell;
  g.low_ = low;
  const Eigen::Vector3d extent = (high - low) * g.inverse_cell_;
  if (!(extent.prod() < static_cast<double>(max_cells))) return std::nullopt;  // also rules out overflow
  g.nx_ = static_cast<std::int64_t>(std::floor(extent.x())) + 1;
  g.ny_ = static_cast<std::int64_t>(std::floor(extent.y())) + 1;
  g.nz_ = static_cast<std::int64_t>(std::floor(extent.z())) + 1;
  const std::int64_t cells = g.nx_ * g.ny_ * g.nz_;
  if (cells > static_cast<std::int64_t>(max_cells)) return std::nullopt;

  const Eigen::Index n = points.rows();
  std::vector<std::uint32_t> cell_of(static_cast<std::size_t>(n));
  g.start_.assign(static_cast<std::size_t>(cells) + 1, 0);
  for (Eigen::Index i = 0; i < n; ++i) {
    const Eigen::Vector3d c = (points.row(i).transpose() - low) * g.inverse_cell_;
    const std::int64_t ix = std::clamp<std::int64_t>(static_cast<std::int64_t>(c.x()), 0, g.nx_ - 1);
    const std::int64_t iy = std::clamp<std::int64_t>(static_cast<std::int64_t>(c.y()), 0, g.ny_ - 1);
    const std::int64_t iz = std::clamp<std::int64_t>(static_cast<std::int64_t>(c.z()), 0, g.nz_ - 1);
    const auto k = static_cast<std::uint32_t>((ix * g.ny_ + iy) * g.nz_ + iz);
    cell_of[static_cast<std::size_t>(i)] = k;
    ++g.start_[k + 1];
  }
  for (std::size_t c = 1; c < g.start_.size(); ++c) g.start_[c] += g.start_[c - 1];
  g.points_.resize(static_cast<std::size_t>(n));
  std::vector<std::uint32_t> next(g.start_.begin(), g.start_.end() - 1);
  for (Eigen::Index i = 0; i < n; ++i) {
    const std::uint32_t at = next[cell_of[static_cast<std::size_t>(i)]]++;
    g.points_[at] = {points(i, 0), points(i, 1), points(i, 2), static_cast<std::uint32_t>(i)};
  }
  return g;
}

int RadiusGrid::NearestWithin(const Eigen::Vector3d& query, double radius, int k, std::uint32_t* indices,
                              double* squared_distances) const {
  k = std::min(k, kMaxK);
  if (k <= 0 || points_.empty()) return 0;
  const double bound = radius * radius;
  const Eigen::Vector3d c = (query - low_) * inverse_cell_;
  // A point two cells away along any axis lies more than a cell, so beyond the radius, from the query.
  if (!(c.x() > -1.0 && c.y() > -1.0 && c.z() > -1.0 && c.x() < static_cast<double>(nx_ + 1) &&
        c.y() < static_cast<double>(ny_ + 1) && c.z() < static_cast<double>(nz_ + 1))) {
    return 0;
  }
  const auto ix = static_cast<std::int64_t>(std::floor(c.x()));
  const auto iy = static_cast<std::int64_t>(std::floor(c.y()));
  const auto iz = static_cast<std::int64_t>(std::floor(c.z()));
  // The squared gap from the query to cell j along one axis (0 inside it), in mm^2.
  auto gap2 = [&](double coordinate, double low, std::int64_t j) {
    const double below = low + static_cast<double>(j) * cell_ - coordinate;
    const double above = coordinate - (low + static_cast<double>(j + 1) * cell_);
    // Less a margin for rounding: a point binned in cell j may lie an ulp outside its box.
    const double g = std::max(std::max(below, above) - 1e-9 * cell_, 0.0);
    return g * g;
  };
  // The up to 27 non-empty cells around the query's that may hold a point within the radius, nearest first.
  struct Cell {
    double gap2;
    std::uint32_t begin, end;
  };
  Cell cells[27];
  int m = 0;
  const std::int64_t z0 = std::max<std::int64_t>(iz - 1, 0), z1 = std::min(iz + 1, nz_ - 1);
  double gz[3] = {0.0, 0.0, 0.0};
  for (std::int64_t z = z0; z <= z1; ++z) gz[z - z0] = gap2(query.z(), low_.z(), z);
  for (std::int64_t x = std::max<std::int64_t>(ix - 1, 0); x <= std::min(ix + 1, nx_ - 1); ++x) {
    const double gx = gap2(query.x(), low_.x(), x);
    for (std::int64_t y = std::max<std::int64_t>(iy - 1, 0); y <= std::min(iy + 1, ny_ - 1); ++y) {
      const double gxy = gx + gap2(query.y(), low_.y(), y);
      if (!(gxy < bound)) continue;
      const std::int64_t base = (x * ny_ + y) * nz_;
      for (std::int64_t z = z0; z <= z1; ++z) {
        const Cell cell{gxy + gz[z - z0], start_[static_cast<std::size_t>(base + z)],
                        start_[static_cast<std::size_t>(base + z) + 1]};
        if (cell.begin == cell.end || !(cell.gap2 < bound)) continue;
        int at = m++;
        for (; at > 0 && cells[at - 1].gap2 > cell.gap2; --at) cells[at] = cells[at - 1];
        cells[at] = cell;
      }
    }
  }
  int count = 0;
  double worst = bound;  // a point must be nearer than this to count: the bound, then the k-th nearest
  for (int j = 0; j < m && cells[j].gap2 < worst; ++j) {
    for (std::uint32_t p = cells[j].begin; p < cells[j].end; ++p) {
      const Point& v = points_[p];
      const double dx = v.x - query.x(), dy = v.y - query.y(), dz = v.z - query.z();
      const double d = dx * dx + dy * dy + dz * dz;
      if (!(d < worst)) continue;
      int at = count < k ? count++ : k - 1;
      for (; at > 0 && squared_distances[at - 1] > d; --at) {
        squared_distances[at] = squared_distances[at - 1];
        indices[at] = indices[at - 1];
      }
      squared_distances[at] = d;
      indices[at] = v.row;
      if (count == k) worst = squared_distances[k - 1];
    }
  }
  return count;
}

}  // namespace pectus::icp_detail
