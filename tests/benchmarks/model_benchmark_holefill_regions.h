// model_benchmark: the measures of the hole-fill benchmark (model_benchmark_holefill.h): error statistics
// inside and at the border, and the size of the region each removed disk takes out of a scan together
// with the scan's own holes it touches.
#pragma once

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <vector>

#include "registration/kdtree.h"
#include "shape/model/hole_fill_validation.h"

namespace pectus::bench {

/// Max and RMS of |error| over a set of vertices.
struct ErrorStats {
  double max = 0.0, sum_sq = 0.0;
  Eigen::Index count = 0;
  void Add(double e) { max = std::max(max, std::abs(e)), sum_sq += e * e, ++count; }
  void Add(const ErrorStats& o) { max = std::max(max, o.max), sum_sq += o.sum_sq, count += o.count; }
  double rms() const { return count > 0 ? std::sqrt(sum_sq / double(count)) : 0.0; }
  nlohmann::json Json() const { return {{"max_mm", max}, {"rms_mm", rms()}, {"vertices", count}}; }
};

/// Errors of one resampling with disks removed, inside (disk 0) and at the border (the others).
struct HoleFillErrors {
  ErrorStats vs_untouched[2], vs_untouched_on_data[2], vs_truth[2], vs_truth_on_data[2],
      untouched_vs_truth[2], untouched_vs_truth_on_data[2], true_skin[2];
  void Add(const HoleFillErrors& o) {
    for (int p = 0; p < 2; ++p) {
      vs_untouched[p].Add(o.vs_untouched[p]), vs_untouched_on_data[p].Add(o.vs_untouched_on_data[p]);
      vs_truth[p].Add(o.vs_truth[p]), untouched_vs_truth[p].Add(o.untouched_vs_truth[p]);
      vs_truth_on_data[p].Add(o.vs_truth_on_data[p]),
          untouched_vs_truth_on_data[p].Add(o.untouched_vs_truth_on_data[p]);
      true_skin[p].Add(o.true_skin[p]);
    }
  }
  nlohmann::json Json() const {
    nlohmann::json j;
    const char* place[2] = {"inside", "border"};
    for (int p = 0; p < 2; ++p) {
      j[place[p]] = {{"holed_vs_untouched", vs_untouched[p].Json()},
                     {"holed_vs_untouched_where_it_has_data", vs_untouched_on_data[p].Json()},
                     {"holed_vs_truth", vs_truth[p].Json()},
                     {"holed_vs_truth_where_the_untouched_scan_has_data", vs_truth_on_data[p].Json()},
                     {"untouched_vs_truth", untouched_vs_truth[p].Json()},
                     {"untouched_vs_truth_where_it_has_data", untouched_vs_truth_on_data[p].Json()},
                     {"true_skin_holed_vs_true_skin", true_skin[p].Json()}};
    }
    return j;
  }
};

/// A grid vertex is in a hole of the scan itself when the surface vertex nearest to it lies farther than
/// this from the merged scan points (the reconstruction's per-vertex "data_distance").
constexpr double kScanHoleMm = 2.0;
/// The acceptance line's removed regions: up to this size (mm) across.
constexpr double kMaxRegionMm = 30.0;

/// Distance (mm) from each grid vertex to the scan's data: the "data_distance" of the surface vertex
/// nearest to it (zero where the surface carries none). Unlike the resampler's data_gap_mm, which is
/// measured to the mesh, this sees the holes that the reconstruction bridged.
inline Eigen::VectorXd ScanDataDistanceOnGrid(const TriangleMesh& surface, const TriangleMesh& grid) {
  Eigen::VectorXd d = Eigen::VectorXd::Zero(grid.vertices.size());
  const auto it = surface.vertices.scalars.find("data_distance");
  if (it == surface.vertices.scalars.end()) return d;
  const KdTree3 tree(surface.vertices.positions);
  for (Eigen::Index k = 0; k < d.size(); ++k) {
    std::uint32_t i = 0;
    double squared = 0.0;
    if (tree.Nearest(grid.vertices.positions.row(k).transpose(), &i, &squared)) d[k] = it->second[i];
  }
  return d;
}

/// The size (mm) of the region each disk removes: the diameter, in the grid's (u, v), of the union of
/// the disk and the scan's own hole vertices (scan_distance > kScanHoleMm) 4-connected to it; at least
/// the disk's diameter. disk_of[k]: the disk holding grid vertex k, or -1.
inline std::vector<double> RemovedRegionSizes(const std::vector<RemovedDisk>& disks, const GridSize& grid,
                                              const Eigen::VectorXd& u, const Eigen::VectorXd& v,
                                              const Eigen::VectorXd& scan_distance,
                                              std::vector<int>* disk_of) {
  disk_of->assign(std::size_t(grid.sternal) * grid.lateral, -1);
  for (int i = 0; i < grid.sternal; ++i)
    for (int j = 0; j < grid.lateral; ++j)
      for (std::size_t d = 0; d < disks.size(); ++d)
        if ((*disk_of)[grid.Index(i, j)] < 0 &&
            std::hypot(u[j] - disks[d].u, v[i] - disks[d].v) <= disks[d].radius_mm)
          (*disk_of)[grid.Index(i, j)] = int(d);
  std::vector<double> sizes;
  for (std::size_t d = 0; d < disks.size(); ++d) {
    std::vector<char> in(disk_of->size(), 0);
    std::vector<std::pair<int, int>> region, todo;
    for (int i = 0; i < grid.sternal; ++i)
      for (int j = 0; j < grid.lateral; ++j)
        if ((*disk_of)[grid.Index(i, j)] == int(d)) in[grid.Index(i, j)] = 1, todo.push_back({i, j});
    while (!todo.empty()) {
      const auto [i, j] = todo.back();
      todo.pop_back();
      region.push_back({i, j});
      for (const auto& [di, dj] : {std::pair{1, 0}, {-1, 0}, {0, 1}, {0, -1}}) {
        const int a = i + di, b = j + dj;
        if (a < 0 || b < 0 || a >= grid.sternal || b >= grid.lateral) continue;
        const Eigen::Index k = grid.Index(a, b);
        if (in[k] || scan_distance[k] <= kScanHoleMm) continue;
        in[k] = 1, todo.push_back({a, b});
      }
    }
    double diameter = 2.0 * disks[d].radius_mm;
    for (const auto& [i, j] : region)
      for (const auto& [a, b] : region) diameter = std::max(diameter, std::hypot(u[j] - u[b], v[i] - v[a]));
    sizes.push_back(diameter);
  }
  return sizes;
}

}  // namespace pectus::bench
