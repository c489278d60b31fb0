// pectus: a uniform grid for the k nearest points within a radius (registration/internal/radius_grid.h).
#include "registration/internal/radius_grid.h"

#include <algorithm>
#include <cmath>
#include <limits>

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
  // The query's cell (-1 or n along an axis when it lies just outside the grid).
  const std::int64_t own[3] = {static_cast<std::int64_t>(c.x() + 1.0) - 1,
                               static_cast<std::int64_t>(c.y() + 1.0) - 1,
                               static_cast<std::int64_t>(c.z() + 1.0) - 1};
  const std::int64_t size[3] = {nx_, ny_, nz_};
  // Along each axis, the squared gap from the query to the cells before, at and after its own (mm^2;
  // infinite outside the grid), less a margin for rounding: a point binned in a cell may lie an ulp
  // outside its box.
  double gap2[3][3];
  for (int a = 0; a < 3; ++a) {
    const double margin = 1e-9 * cell_;
    const double below = std::max(query[a] - (low_[a] + static_cast<double>(own[a]) * cell_) - margin, 0.0);
    const double above = std::max(low_[a] + static_cast<double>(own[a] + 1) * cell_ - query[a] - margin, 0.0);
    auto inside = [&](std::int64_t j) { return j >= 0 && j < size[a]; };
    constexpr double kOutside = std::numeric_limits<double>::infinity();
    gap2[a][0] = inside(own[a] - 1) ? below * below : kOutside;
    gap2[a][1] = inside(own[a]) ? 0.0 : kOutside;
    gap2[a][2] = inside(own[a] + 1) ? above * above : kOutside;
  }
  int count = 0;
  double worst = bound;  // a point must be nearer than this to count: the bound, then the k-th nearest
  // Scans the cell at offsets (ox, oy, oz) in {0, 1, 2} from the one before the query's, unless its
  // box lies beyond the current k-th nearest.
  auto scan = [&](int ox, int oy, int oz) {
    if (!(gap2[0][ox] + gap2[1][oy] + gap2[2][oz] < worst)) return;
    const auto cell =
        static_cast<std::size_t>(((own[0] + ox - 1) * ny_ + own[1] + oy - 1) * nz_ + own[2] + oz - 1);
    for (std::uint32_t p = start_[cell], end = start_[cell + 1]; p < end; ++p) {
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
  };
  // The query's own cell first: on a surface a few times denser than the cell it holds the k nearest
  // points, so that the bound falls to their distance and most of the 26 others are skipped unread. Then
  // the six sharing a face, the nearer of each pair first, then the twelve sharing an edge and the eight
  // sharing a corner. The order changes which cells are read, never the answer.
  scan(1, 1, 1);
  for (int a = 0; a < 3; ++a) {
    const int nearer = gap2[a][0] <= gap2[a][2] ? 0 : 2;
    int o[3] = {1, 1, 1};
    o[a] = nearer;
    scan(o[0], o[1], o[2]);
    o[a] = 2 - nearer;
    scan(o[0], o[1], o[2]);
  }
  for (int ox = 0; ox < 3; ++ox) {
    for (int oy = 0; oy < 3; ++oy) {
      for (int oz = 0; oz < 3; ++oz) {
        if ((ox != 1) + (oy != 1) + (oz != 1) >= 2) scan(ox, oy, oz);
      }
    }
  }
  return count;
}

}  // namespace pectus::icp_detail
