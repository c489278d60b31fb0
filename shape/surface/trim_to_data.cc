#include "shape/surface/trim_to_data.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>
#include <vector>

#include "shape/core/error.h"

namespace pectus {
namespace {

// Neighbour of each face across each of its edges (edge i joins corners i and i+1), -1 for a border
// edge or an edge with more than two faces.
std::vector<std::array<std::int32_t, 3>> FaceNeighbours(const Faces3& faces) {
  const Eigen::Index nf = faces.rows();
  std::vector<std::pair<std::uint64_t, std::int32_t>> edges(std::size_t(nf) * 3);
  for (Eigen::Index f = 0; f < nf; ++f) {
    for (int i = 0; i < 3; ++i) {
      const std::uint32_t a = std::uint32_t(faces(f, i)), b = std::uint32_t(faces(f, (i + 1) % 3));
      const std::uint64_t key = (std::uint64_t(std::min(a, b)) << 32) | std::max(a, b);
      edges[std::size_t(f) * 3 + std::size_t(i)] = {key, std::int32_t(f * 3 + i)};
    }
  }
  std::sort(edges.begin(), edges.end());
  std::vector<std::array<std::int32_t, 3>> neighbours(std::size_t(nf), {-1, -1, -1});
  for (std::size_t s = 0; s < edges.size();) {
    std::size_t e = s;
    while (e < edges.size() && edges[e].first == edges[s].first) ++e;
    if (e - s == 2) {
      const std::int32_t a = edges[s].second, b = edges[s + 1].second;
      neighbours[std::size_t(a / 3)][std::size_t(a % 3)] = b / 3;
      neighbours[std::size_t(b / 3)][std::size_t(b % 3)] = a / 3;
    }
    s = e;
  }
  return neighbours;
}

// Connected components of the faces with keep[f], joined across edges; -1 for the others.
std::int32_t Components(const std::vector<std::array<std::int32_t, 3>>& neighbours,
                        const std::vector<char>& keep, std::vector<std::int32_t>* label) {
  label->assign(neighbours.size(), -1);
  std::int32_t count = 0;
  std::vector<std::int32_t> stack;
  for (std::size_t f = 0; f < neighbours.size(); ++f) {
    if (!keep[f] || (*label)[f] >= 0) continue;
    (*label)[f] = count;
    stack.push_back(std::int32_t(f));
    while (!stack.empty()) {
      const std::int32_t g = stack.back();
      stack.pop_back();
      for (const std::int32_t h : neighbours[std::size_t(g)]) {
        if (h >= 0 && keep[std::size_t(h)] && (*label)[std::size_t(h)] < 0) {
          (*label)[std::size_t(h)] = count;
          stack.push_back(h);
        }
      }
    }
    ++count;
  }
  return count;
}

// Removes, at every vertex whose kept faces form more than one fan, all fans but the largest. Returns
// the number of fans removed.
std::int64_t RepairFans(const Faces3& faces, const std::vector<std::array<std::int32_t, 3>>& neighbours,
                        Eigen::Index num_vertices, std::vector<char>* keep) {
  std::int64_t removed = 0;
  for (int pass = 0; pass < 16; ++pass) {
    std::vector<std::int32_t> offsets(std::size_t(num_vertices) + 1, 0);
    for (Eigen::Index f = 0; f < faces.rows(); ++f)
      if ((*keep)[std::size_t(f)])
        for (int i = 0; i < 3; ++i) ++offsets[std::size_t(faces(f, i)) + 1];
    std::partial_sum(offsets.begin(), offsets.end(), offsets.begin());
    std::vector<std::int32_t> incident(std::size_t(offsets.back()));
    std::vector<std::int32_t> fill(offsets.begin(), offsets.end() - 1);
    for (Eigen::Index f = 0; f < faces.rows(); ++f)
      if ((*keep)[std::size_t(f)])
        for (int i = 0; i < 3; ++i) incident[std::size_t(fill[std::size_t(faces(f, i))]++)] = std::int32_t(f);

    std::int64_t removed_now = 0;
    std::vector<std::int32_t> parent;
    for (Eigen::Index v = 0; v < num_vertices; ++v) {
      const std::int32_t b = offsets[std::size_t(v)], e = offsets[std::size_t(v) + 1];
      if (e - b < 2) continue;
      const std::int32_t n = e - b;
      parent.resize(std::size_t(n));
      std::iota(parent.begin(), parent.end(), 0);
      auto find = [&](std::int32_t x) {
        while (parent[std::size_t(x)] != x)
          x = parent[std::size_t(x)] = parent[std::size_t(parent[std::size_t(x)])];
        return x;
      };
      for (std::int32_t i = 0; i < n; ++i) {
        const std::int32_t f = incident[std::size_t(b + i)];
        for (int k = 0; k < 3; ++k) {
          // Only the two edges of f that contain v join fans at v.
          if (faces(f, k) != v && faces(f, (k + 1) % 3) != v) continue;
          const std::int32_t g = neighbours[std::size_t(f)][std::size_t(k)];
          if (g < 0 || !(*keep)[std::size_t(g)]) continue;
          for (std::int32_t j = 0; j < n; ++j)
            if (incident[std::size_t(b + j)] == g) parent[std::size_t(find(i))] = find(j);
        }
      }
      std::vector<std::int32_t> size(std::size_t(n), 0);
      for (std::int32_t i = 0; i < n; ++i) ++size[std::size_t(find(i))];
      const auto largest = std::int32_t(std::max_element(size.begin(), size.end()) - size.begin());
      if (size[std::size_t(largest)] == n) continue;
      for (std::int32_t i = 0; i < n; ++i) {
        if (find(i) != largest) (*keep)[std::size_t(incident[std::size_t(b + i)])] = 0;
      }
      std::int32_t fans = 0;
      for (std::int32_t i = 0; i < n; ++i) fans += (size[std::size_t(i)] > 0);
      removed_now += fans - 1;
    }
    removed += removed_now;
    if (removed_now == 0) break;
  }
  return removed;
}

}  // namespace

bool TrimOptions::IsValid(std::string* why) const {
  auto fail = [&](const char* text) {
    if (why) *why = text;
    return false;
  };
  if (!(margin_mm > 0.0) || !std::isfinite(margin_mm)) return fail("trim margin must be > 0 mm");
  if (!(max_hole_size_mm >= 0.0) || !std::isfinite(max_hole_size_mm))
    return fail("hole size must be >= 0 mm");
  if (!(min_component_fraction >= 0.0 && min_component_fraction <= 1.0)) {
    return fail("minimum component fraction must be in [0, 1]");
  }
  return true;
}

TrimResult TrimToData(const KdTree3& tree, TriangleMesh* mesh, const TrimOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) ThrowUsage(why);
  TrimResult result;
  const Points3& vertices = mesh->vertices.positions;
  const Faces3& faces = mesh->faces;
  const Eigen::Index nv = vertices.rows(), nf = faces.rows();

  // Distance from every vertex to the data.
  Eigen::VectorXd distance(nv);
#pragma omp parallel for schedule(static)
  for (Eigen::Index v = 0; v < nv; ++v) {
    std::uint32_t idx;
    double d2 = 0.0;
    tree.Nearest(vertices.row(v).transpose(), &idx, &d2);
    distance(v) = std::sqrt(d2);
  }

  // Uncovered regions: keep the enclosed ones no wider than max_hole_size_mm.
  const auto neighbours = FaceNeighbours(faces);
  std::vector<char> keep(static_cast<std::size_t>(nf)), uncovered(static_cast<std::size_t>(nf));
  for (Eigen::Index f = 0; f < nf; ++f) {
    const double d = std::max({distance(faces(f, 0)), distance(faces(f, 1)), distance(faces(f, 2))});
    keep[std::size_t(f)] = d <= options.margin_mm;
    uncovered[std::size_t(f)] = !keep[std::size_t(f)];
  }
  std::vector<std::int32_t> label;
  const std::int32_t regions = Components(neighbours, uncovered, &label);
  std::vector<char> touches_border(std::size_t(regions), 0);
  std::vector<double> width(std::size_t(regions), 0.0);
  for (Eigen::Index f = 0; f < nf; ++f) {
    const std::int32_t r = label[std::size_t(f)];
    if (r < 0) continue;
    for (int i = 0; i < 3; ++i) {
      if (neighbours[std::size_t(f)][std::size_t(i)] < 0) touches_border[std::size_t(r)] = 1;
      width[std::size_t(r)] = std::max(width[std::size_t(r)], 2.0 * distance(faces(f, i)));
    }
  }
  std::vector<char> fill(std::size_t(regions), 0);
  for (std::int32_t r = 0; r < regions; ++r) {
    if (touches_border[std::size_t(r)]) continue;
    if (width[std::size_t(r)] <= options.max_hole_size_mm) {
      fill[std::size_t(r)] = 1;
      ++result.holes_filled;
      result.largest_hole_filled_mm = std::max(result.largest_hole_filled_mm, width[std::size_t(r)]);
    } else {
      ++result.holes_left_open;
    }
  }
  for (Eigen::Index f = 0; f < nf; ++f) {
    if (label[std::size_t(f)] >= 0 && fill[std::size_t(label[std::size_t(f)])]) keep[std::size_t(f)] = 1;
  }

  // One fan per vertex, then no small pieces.
  result.fans_removed = RepairFans(faces, neighbours, nv, &keep);
  const std::int32_t pieces = Components(neighbours, keep, &label);
  std::vector<std::int64_t> piece_size(std::size_t(pieces), 0);
  for (Eigen::Index f = 0; f < nf; ++f)
    if (label[std::size_t(f)] >= 0) ++piece_size[std::size_t(label[std::size_t(f)])];
  const std::int64_t largest = pieces > 0 ? *std::max_element(piece_size.begin(), piece_size.end()) : 0;
  for (std::int32_t p = 0; p < pieces; ++p) {
    if (double(piece_size[std::size_t(p)]) < options.min_component_fraction * double(largest)) {
      ++result.components_removed;
      piece_size[std::size_t(p)] = -1;
    }
  }
  for (Eigen::Index f = 0; f < nf; ++f) {
    if (keep[std::size_t(f)] && piece_size[std::size_t(label[std::size_t(f)])] < 0) keep[std::size_t(f)] = 0;
  }

  // Compact.
  std::vector<std::int32_t> new_index(std::size_t(nv), -1);
  Eigen::Index kept_faces = 0, kept_vertices = 0;
  for (Eigen::Index f = 0; f < nf; ++f) {
    if (!keep[std::size_t(f)]) continue;
    ++kept_faces;
    for (int i = 0; i < 3; ++i) {
      std::int32_t& ni = new_index[std::size_t(faces(f, i))];
      if (ni < 0) ni = std::int32_t(kept_vertices++);
    }
  }
  TriangleMesh out;
  out.vertices.positions.resize(kept_vertices, 3);
  Eigen::VectorXd kept_distance(kept_vertices);
  for (Eigen::Index v = 0; v < nv; ++v) {
    const std::int32_t ni = new_index[std::size_t(v)];
    if (ni < 0) continue;
    out.vertices.positions.row(ni) = vertices.row(v);
    kept_distance(ni) = distance(v);
  }
  out.vertices.scalars["data_distance"] = kept_distance;
  out.faces.resize(kept_faces, 3);
  Eigen::Index k = 0;
  for (Eigen::Index f = 0; f < nf; ++f) {
    if (!keep[std::size_t(f)]) continue;
    for (int i = 0; i < 3; ++i) out.faces(k, i) = new_index[std::size_t(faces(f, i))];
    ++k;
  }
  result.faces_removed = nf - kept_faces;
  const auto out_neighbours = FaceNeighbours(out.faces);
  for (const auto& n : out_neighbours)
    for (const std::int32_t g : n) result.boundary_edges += (g < 0);
  *mesh = std::move(out);
  return result;
}

}  // namespace pectus
