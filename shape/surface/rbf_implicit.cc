#include "shape/surface/rbf_implicit.h"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <deque>
#include <numeric>
#include <optional>
#include <vector>

#include "registration/kdtree.h"
#include "shape/core/error.h"
#include "shape/surface/internal/sparse_grid.h"
#include "shape/surface/local_rbf.h"
#include "shape/surface/rbf_levels.h"

namespace pectus {

bool RbfImplicitOptions::IsValid(std::string* why) const {
  auto fail = [&](const std::string& text) {
    if (why) *why = text;
    return false;
  };
  auto positive = [](double v) { return v > 0.0 && std::isfinite(v); };
  if (!positive(cell_size_mm)) return fail("cell size must be > 0 mm");
  if (!(fit_radius_factor >= 1.0) || !std::isfinite(fit_radius_factor)) {
    return fail("fit radius factor must be >= 1 (a fit must cover its cell's support)");
  }
  if (!(hole_context >= 0.0) || !std::isfinite(hole_context)) return fail("hole context must be >= 0");
  if (!positive(centre_spacing_mm)) return fail("centre spacing must be > 0 mm");
  if (!positive(off_surface_distance_mm)) return fail("off-surface distance must be > 0 mm");
  if (!positive(off_surface_weight)) return fail("off-surface weight must be > 0");
  if (!(smoothing >= 0.0) || !std::isfinite(smoothing)) return fail("smoothing must be >= 0");
  if (!(max_fill_distance_mm >= 0.0) || !std::isfinite(max_fill_distance_mm)) {
    return fail("max fill distance must be >= 0 mm");
  }
  if (max_centres < 4 || max_centres > 400) return fail("max centres must be in [4, 400]");
  if (!(max_hole_size_mm >= 0.0) || !std::isfinite(max_hole_size_mm))
    return fail("max hole size must be >= 0 mm");
  return true;
}

struct RbfImplicit::Impl {
  RbfImplicitOptions options;
  std::deque<RbfLevel> levels;       // [0] constraints at centre_spacing_mm / 2, [1] centres, coarser after
  Eigen::Vector3d grid_origin;       // corner of cell (0, 0, 0)
  GridKeyMap<std::int32_t> cell_of;  // cell key -> index into fits, -1 = undefined
  std::vector<LocalRbf> fits;
  std::vector<Eigen::Vector3d> fit_centres;
  std::int64_t undefined_cells = 0;

  Eigen::Vector3d CellCentre(GridKey key) const {
    return grid_origin + (UnpackGridKey(key).cast<double>().array() + 0.5).matrix() * options.cell_size_mm;
  }

  // The local fit of one cell, or nullopt if the cell is undefined.
  std::optional<LocalRbf> FitCell(GridKey key) const {
    const Eigen::Vector3d c = CellCentre(key);
    std::uint32_t nearest;
    double d2;
    if (!levels[0].tree->NearestWithin(c, options.max_fill_distance_mm, &nearest, &d2)) return std::nullopt;
    // How far the cell is from data along the surface: the offset from the nearest point within its
    // tangent plane (a cell just above or below the data has none; one over a hole, the hole's radius).
    const Eigen::Vector3d offset = c - levels[0].positions.row(nearest).transpose();
    const Eigen::Vector3d normal = levels[0].normals.row(nearest).transpose();
    const Eigen::Vector3d tangential = offset - normal.dot(offset) * normal;
    const double along = tangential.norm();
    // Over a hole at most max_hole_size_mm wide, the far rim lies within max_hole_size_mm - along of the
    // cell, beyond it as seen from the nearest data point p; beyond the edge of the data nothing does (every
    // data point x has (x - c).(c - p) < 0), and the cell is left undefined rather than fitted and then
    // trimmed away.
    const double edge_test = std::max(0.5 * options.cell_size_mm, 0.2 * options.max_hole_size_mm);
    if (options.max_hole_size_mm > 0.0 && along > edge_test) {
      const double reach = options.max_hole_size_mm - along + 0.5 * options.cell_size_mm;
      if (reach <= 0.0) return std::nullopt;
      std::vector<std::pair<std::uint32_t, double>> around;
      levels[0].tree->Radius(c, reach, &around, false);
      const bool far_side = std::any_of(around.begin(), around.end(), [&](const auto& hit) {
        return (levels[0].positions.row(hit.first).transpose() - c).dot(offset) > 0.0;
      });
      if (!far_side) return std::nullopt;
    }
    const double radius = options.fit_radius_factor * options.cell_size_mm + options.hole_context * along;
    // Centres: the finest level with at most 4 max_centres in the ball, thinned evenly (the k-d tree
    // returns them in leaf order, so every n-th is spread over the ball) to at most max_centres.
    // Constraints: the finest level with at most 8 max_centres in the ball, and never coarser than the
    // centres' parent level.
    std::vector<std::pair<std::uint32_t, double>> centres, rows;
    const std::size_t max_centres = std::size_t(options.max_centres);
    std::size_t k = 1;
    for (; k + 1 < levels.size(); ++k) {
      levels[k].tree->Radius(c, radius, &centres, false);
      if (centres.size() <= 4 * max_centres) break;
    }
    if (k + 1 == levels.size()) levels[k].tree->Radius(c, radius, &centres, false);
    if (centres.size() > max_centres) {
      const std::size_t stride = (centres.size() + max_centres - 1) / max_centres;
      std::size_t kept = 0;
      for (std::size_t i = 0; i < centres.size(); i += stride) centres[kept++] = centres[i];
      centres.resize(kept);
    }
    std::size_t j = 0;
    for (; j + 1 < k; ++j) {
      levels[j].tree->Radius(c, radius, &rows, false);
      if (rows.size() <= 8 * max_centres) break;
    }
    if (j + 1 == k) levels[j].tree->Radius(c, radius, &rows, false);
    const LocalRbfProblem problem =
        LocalProblem(levels[j], rows, levels[k], centres, c, radius, options.off_surface_weight);
    LocalRbf fit;
    if (!fit.Fit(problem, options.smoothing)) return std::nullopt;
    return fit;
  }

  // Fits every cell that a query needs and that is not known yet.
  void EnsureCells(const Points3& queries) {
    const Eigen::Index n = queries.rows();
    const double h = options.cell_size_mm;
    std::vector<std::vector<GridKey>> missing(static_cast<std::size_t>(omp_get_max_threads()));
#pragma omp parallel
    {
      std::vector<GridKey>& mine = missing[std::size_t(omp_get_thread_num())];
      GridKey last[8];
      std::fill(last, last + 8, ~GridKey{0});
#pragma omp for schedule(static)
      for (Eigen::Index q = 0; q < n; ++q) {
        const Eigen::Vector3d u =
            (queries.row(q).transpose() - grid_origin) / h - Eigen::Vector3d::Constant(0.5);
        const std::int64_t a = std::int64_t(std::floor(u.x())), b = std::int64_t(std::floor(u.y())),
                           cc = std::int64_t(std::floor(u.z()));
        int slot = 0;
        for (int dz = 0; dz < 2; ++dz)
          for (int dy = 0; dy < 2; ++dy)
            for (int dx = 0; dx < 2; ++dx, ++slot) {
              if (!GridIndexInRange(a + dx, b + dy, cc + dz)) continue;
              const GridKey key = PackGridKey(a + dx, b + dy, cc + dz);
              if (key == last[slot]) continue;  // neighbouring queries share cells
              last[slot] = key;
              if (!cell_of.Find(key)) mine.push_back(key);
            }
      }
    }
    std::vector<GridKey> todo;
    {
      GridKeyMap<char> seen(1024);
      for (const auto& list : missing)
        for (GridKey key : list)
          if (seen.Insert(key, 1).second) todo.push_back(key);
    }
    if (todo.empty()) return;
    std::sort(todo.begin(), todo.end());
    std::vector<std::optional<LocalRbf>> fitted(todo.size());
#pragma omp parallel for schedule(dynamic, 16)
    for (std::size_t t = 0; t < todo.size(); ++t) fitted[t] = FitCell(todo[t]);
    for (std::size_t t = 0; t < todo.size(); ++t) {
      if (fitted[t]) {
        cell_of.Insert(todo[t], std::int32_t(fits.size()));
        fits.push_back(std::move(*fitted[t]));
        fit_centres.push_back(CellCentre(todo[t]));
      } else {
        cell_of.Insert(todo[t], -1);
        ++undefined_cells;
      }
    }
  }

  double EvaluateOne(const Eigen::Vector3d& x) const {
    const double h = options.cell_size_mm;
    const Eigen::Vector3d u = (x - grid_origin) / h - Eigen::Vector3d::Constant(0.5);
    const std::int64_t a = std::int64_t(std::floor(u.x())), b = std::int64_t(std::floor(u.y())),
                       c = std::int64_t(std::floor(u.z()));
    double sum = 0.0, weight = 0.0;
    for (int dz = 0; dz < 2; ++dz)
      for (int dy = 0; dy < 2; ++dy)
        for (int dx = 0; dx < 2; ++dx) {
          if (!GridIndexInRange(a + dx, b + dy, c + dz)) continue;
          const std::int32_t* cell = cell_of.Find(PackGridKey(a + dx, b + dy, c + dz));
          if (cell == nullptr || *cell < 0) continue;
          const double w = WendlandC2((x - fit_centres[std::size_t(*cell)]).norm() / h);
          if (w <= 0.0) continue;
          sum += w * fits[std::size_t(*cell)].Evaluate(x);
          weight += w;
        }
    return weight > 1e-9 ? sum / weight : std::numeric_limits<double>::quiet_NaN();
  }
};

RbfImplicit::RbfImplicit(const Points3& positions, const Points3& normals, const RbfImplicitOptions& options)
    : RbfImplicit(positions, normals, Eigen::VectorXd::Ones(positions.rows()), options) {}

RbfImplicit::RbfImplicit(const Points3& positions, const Points3& normals, const Eigen::VectorXd& counts,
                         const RbfImplicitOptions& options)
    : impl_(std::make_unique<Impl>()) {
  std::string why;
  if (!options.IsValid(&why)) ThrowUsage("RBF implicit: " + why);
  if (normals.rows() != positions.rows()) ThrowUsage("RBF implicit: one normal per point is needed");
  if (counts.size() != positions.rows() || !(counts.array() > 0.0).all()) {
    ThrowUsage("RBF implicit: one positive count per point is needed");
  }
  if (positions.rows() < 4) ThrowBadInput("", "RBF implicit: at least 4 points are needed");
  Impl& im = *impl_;
  im.options = options;
  const Bounds3 bounds = ComputeBounds(positions);
  const double margin = options.max_fill_distance_mm + 2.0 * options.cell_size_mm;
  CheckGridFits(bounds.extent().maxCoeff() + 2.0 * margin, options.cell_size_mm, "RBF cell grid");
  im.grid_origin = bounds.min;

  // Level 0 (constraints) at half the centre spacing, level 1 (centres) at the centre spacing, then
  // doubled until a level is small enough to hold every hole cell's centres.
  im.levels.emplace_back();
  AverageByVoxel(positions, normals, counts, 0.5 * options.centre_spacing_mm, &im.levels.back());
  for (double spacing = options.centre_spacing_mm;; spacing *= 2.0) {
    // In place: a level's k-d tree refers to its positions (a deque never moves its elements).
    im.levels.emplace_back();
    const RbfLevel& prev = im.levels[im.levels.size() - 2];
    AverageByVoxel(prev.positions, prev.normals, prev.counts, spacing, &im.levels.back());
    SetOffSurfaceDistances(im.levels[0], options.off_surface_distance_mm, &im.levels.back());
    if (im.levels.back().positions.rows() <= options.max_centres / 2 || im.levels.size() > 24) break;
  }
}

RbfImplicit::~RbfImplicit() = default;

void RbfImplicit::Evaluate(const Points3& queries, Eigen::VectorXd* values) {
  impl_->EnsureCells(queries);
  const Eigen::Index n = queries.rows();
  values->resize(n);
  const Impl& im = *impl_;
#pragma omp parallel for schedule(static)
  for (Eigen::Index q = 0; q < n; ++q) (*values)(q) = im.EvaluateOne(queries.row(q).transpose());
}

RbfFittingAccuracy RbfImplicit::FittingAccuracy() {
  RbfFittingAccuracy acc;
  Eigen::VectorXd s;
  const Points3& constraints = impl_->levels[0].positions;  // the on-surface constraints of the fits
  Evaluate(constraints, &s);
  std::vector<double> abs_values;
  abs_values.reserve(std::size_t(s.size()));
  double sum2 = 0.0;
  for (Eigen::Index i = 0; i < s.size(); ++i) {
    if (!std::isfinite(s(i))) continue;
    abs_values.push_back(std::abs(s(i)));
    sum2 += s(i) * s(i);
  }
  acc.num_on_surface = std::int64_t(abs_values.size());
  if (!abs_values.empty()) {
    acc.on_surface_rms_mm = std::sqrt(sum2 / double(abs_values.size()));
    const auto p95 = abs_values.begin() + std::ptrdiff_t(0.95 * double(abs_values.size() - 1));
    std::nth_element(abs_values.begin(), p95, abs_values.end());
    acc.on_surface_p95_mm = *p95;
    acc.on_surface_max_mm = *std::max_element(abs_values.begin(), abs_values.end());
  }
  const RbfLevel& cl = impl_->levels[1];
  const Eigen::Index m = cl.positions.rows();
  Points3 off(2 * m, 3);
  Eigen::VectorXd target(2 * m);
  Eigen::Index k = 0;
  for (Eigen::Index i = 0; i < m; ++i) {
    for (int side = 0; side < 2; ++side) {
      const double eps = side == 0 ? cl.eps_plus(i) : -cl.eps_minus(i);
      if (eps == 0.0) continue;
      off.row(k) = cl.positions.row(i) + eps * cl.normals.row(i);
      target(k++) = eps;
    }
  }
  off.conservativeResize(k, 3);
  Evaluate(off, &s);
  for (Eigen::Index i = 0; i < k; ++i) {
    if (std::isfinite(s(i)))
      acc.off_surface_max_mm = std::max(acc.off_surface_max_mm, std::abs(s(i) - target(i)));
  }
  acc.num_off_surface = k;
  acc.fitting_accuracy_mm = std::max(acc.on_surface_max_mm, acc.off_surface_max_mm);
  return acc;
}

const Points3& RbfImplicit::Seeds() const { return impl_->levels[1].positions; }
std::int64_t RbfImplicit::num_cells() const { return std::int64_t(impl_->cell_of.size()); }
std::int64_t RbfImplicit::num_undefined_cells() const { return impl_->undefined_cells; }

}  // namespace pectus
