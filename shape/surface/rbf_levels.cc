#include "shape/surface/rbf_levels.h"

#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

#include "shape/surface/internal/sparse_grid.h"

namespace pectus {

void AverageByVoxel(const Points3& positions, const Points3& normals, const Eigen::VectorXd& counts,
                    double spacing, RbfLevel* level) {
  const Eigen::Index n = positions.rows();
  const bool with_normals = normals.rows() == n;
  const Bounds3 b = ComputeBounds(positions);
  CheckGridFits(b.extent().maxCoeff() + spacing, spacing, "RBF centre grid");
  std::vector<std::pair<GridKey, std::uint32_t>> keyed(static_cast<std::size_t>(n));
#pragma omp parallel for schedule(static)
  for (Eigen::Index i = 0; i < n; ++i) {
    const Eigen::Vector3d u = (positions.row(i).transpose() - b.min) / spacing;
    keyed[static_cast<std::size_t>(i)] = {
        PackGridKey(std::int64_t(u.x()), std::int64_t(u.y()), std::int64_t(u.z())), std::uint32_t(i)};
  }
  std::sort(keyed.begin(), keyed.end());
  std::vector<Eigen::Vector3d> pos, nor;
  std::vector<double> cnt;
  pos.reserve(keyed.size() / 4 + 1);
  nor.reserve(keyed.size() / 4 + 1);
  cnt.reserve(keyed.size() / 4 + 1);
  for (std::size_t s = 0; s < keyed.size();) {
    std::size_t e = s;
    while (e < keyed.size() && keyed[e].first == keyed[s].first) ++e;
    if (!with_normals) {
      Eigen::Vector3d sp = Eigen::Vector3d::Zero();
      double sc = 0.0;
      for (std::size_t t = s; t < e; ++t) {
        const Eigen::Index i = keyed[t].second;
        sp += counts(i) * positions.row(i).transpose();
        sc += counts(i);
      }
      pos.push_back(sp / sc);
      cnt.push_back(sc);
      s = e;
      continue;
    }
    const Eigen::Vector3d ref = normals.row(keyed[s].second).transpose();
    for (int side = 0; side < 2; ++side) {
      Eigen::Vector3d sp = Eigen::Vector3d::Zero(), sn = Eigen::Vector3d::Zero();
      double sc = 0.0;
      for (std::size_t t = s; t < e; ++t) {
        const Eigen::Index i = keyed[t].second;
        const Eigen::Vector3d nv = normals.row(i).transpose();
        if ((nv.dot(ref) >= 0.0) != (side == 0)) continue;
        sp += counts(i) * positions.row(i).transpose();
        sn += counts(i) * nv;
        sc += counts(i);
      }
      if (sc > 0.0 && sn.norm() > 1e-12) {
        pos.push_back(sp / sc);
        nor.push_back(sn.normalized());
        cnt.push_back(sc);
      }
    }
    s = e;
  }
  level->spacing = spacing;
  level->positions.resize(Eigen::Index(pos.size()), 3);
  level->normals.resize(Eigen::Index(nor.size()), 3);
  level->counts.resize(Eigen::Index(pos.size()));
  for (std::size_t i = 0; i < pos.size(); ++i) {
    level->positions.row(Eigen::Index(i)) = pos[i].transpose();
    if (with_normals) level->normals.row(Eigen::Index(i)) = nor[i].transpose();
    level->counts(Eigen::Index(i)) = cnt[i];
  }
  level->tree = std::make_unique<KdTree3>(level->positions);
}

void SetOffSurfaceDistances(const RbfLevel& fine, double eps_mm, RbfLevel* level) {
  const Eigen::Index n = level->positions.rows();
  level->eps_plus.resize(n);
  level->eps_minus.resize(n);
#pragma omp parallel for schedule(static)
  for (Eigen::Index i = 0; i < n; ++i) {
    const Eigen::Vector3d p = level->positions.row(i).transpose();
    const Eigen::Vector3d nv = level->normals.row(i).transpose();
    for (int side = 0; side < 2; ++side) {
      double eps = eps_mm;
      const double sign = side == 0 ? 1.0 : -1.0;
      int tries = 0;
      for (; tries < 4; ++tries, eps *= 0.5) {
        std::uint32_t idx;
        double d2;
        fine.tree->Nearest(p + sign * eps * nv, &idx, &d2);
        if (d2 >= 0.49 * eps * eps) break;
      }
      (side == 0 ? level->eps_plus : level->eps_minus)(i) = tries < 4 ? eps : 0.0;
    }
  }
}

LocalRbfProblem LocalProblem(const RbfLevel& row_level, const LevelNeighbours& rows,
                             const RbfLevel& centre_level, const LevelNeighbours& centres,
                             const Eigen::Vector3d& origin, double radius, double off_surface_weight) {
  const RbfLevel& rl = row_level;
  const RbfLevel& cl = centre_level;
  const Eigen::Index m = Eigen::Index(centres.size());
  const Eigen::Index nr = Eigen::Index(rows.size());
  LocalRbfProblem problem;
  problem.origin = origin;
  problem.scale = radius;
  problem.centres.resize(m, 3);
  problem.points.resize(nr + 2 * m, 3);
  problem.values.resize(nr + 2 * m);
  problem.weights.resize(nr + 2 * m);
  for (Eigen::Index r = 0; r < nr; ++r) {
    const auto i = Eigen::Index(rows[std::size_t(r)].first);
    problem.points.row(r) = rl.positions.row(i);
    problem.values(r) = 0.0;
    problem.weights(r) = rl.counts(i) * WendlandC2(std::sqrt(rows[std::size_t(r)].second) / radius);
  }
  Eigen::Index row = nr;
  for (Eigen::Index centre = 0; centre < m; ++centre) {
    const auto i = Eigen::Index(centres[std::size_t(centre)].first);
    problem.centres.row(centre) = cl.positions.row(i);
    const double w = off_surface_weight * cl.counts(i) *
                     WendlandC2(std::sqrt(centres[std::size_t(centre)].second) / radius);
    for (int side = 0; side < 2; ++side) {
      const double eps = side == 0 ? cl.eps_plus(i) : -cl.eps_minus(i);
      if (eps == 0.0 || w <= 0.0) continue;
      problem.points.row(row) = cl.positions.row(i) + eps * cl.normals.row(i);
      problem.values(row) = eps;
      problem.weights(row) = w;
      ++row;
    }
  }
  problem.points.conservativeResize(row, 3);
  problem.values.conservativeResize(row);
  problem.weights.conservativeResize(row);
  return problem;
}

}  // namespace pectus
