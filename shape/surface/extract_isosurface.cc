#include "shape/surface/extract_isosurface.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <vector>

#include "shape/core/error.h"
#include "shape/surface/internal/sparse_grid.h"

namespace pectus {
namespace {

// Corner c of a cube sits at (c & 1, (c >> 1) & 1, (c >> 2) & 1); bit c of a case is set when corner c
// is inside (value < 0).
Eigen::Vector3d CornerOffset(int c) { return {double(c & 1), double((c >> 1) & 1), double((c >> 2) & 1)}; }

struct Edge {
  int c0, c1, axis;  // c1 = c0 + unit step along axis
};

struct CaseTable {
  std::array<Edge, 12> edges{};
  int edge_of[8][8];
  // Triangles per case as triples of edge indices.
  std::array<std::vector<std::array<std::int8_t, 3>>, 256> triangles;
  // Face f = 2 * axis + side: its corners in cyclic order.
  std::array<std::array<int, 4>, 6> faces{};
};

CaseTable BuildTable() {
  CaseTable t;
  int e = 0;
  for (int axis = 0; axis < 3; ++axis) {
    for (int c = 0; c < 8; ++c) {
      if (c & (1 << axis)) continue;
      t.edges[std::size_t(e)] = {c, c | (1 << axis), axis};
      t.edge_of[c][c | (1 << axis)] = t.edge_of[c | (1 << axis)][c] = e;
      ++e;
    }
  }
  for (int axis = 0; axis < 3; ++axis) {
    const int u = (axis + 1) % 3, v = (axis + 2) % 3;
    for (int side = 0; side < 2; ++side) {
      const int base = side << axis;
      t.faces[std::size_t(2 * axis + side)] = {base, base | (1 << u), base | (1 << u) | (1 << v),
                                               base | (1 << v)};
    }
  }
  auto midpoint = [&](int edge) -> Eigen::Vector3d {
    return 0.5 * (CornerOffset(t.edges[std::size_t(edge)].c0) + CornerOffset(t.edges[std::size_t(edge)].c1));
  };

  for (int mask = 0; mask < 256; ++mask) {
    auto inside = [&](int c) { return (mask >> c) & 1; };
    std::array<int, 12> next;
    next.fill(-1);
    for (int f = 0; f < 6; ++f) {
      const auto& q = t.faces[std::size_t(f)];
      const int axis = f / 2;
      Eigen::Vector3d outward = Eigen::Vector3d::Zero();
      outward(axis) = (f % 2) ? 1.0 : -1.0;
      std::vector<std::array<int, 2>> segments;  // pairs of edges
      std::vector<Eigen::Vector3d> refs;         // a point on the inside side of each segment
      int crossings = 0;
      for (int i = 0; i < 4; ++i)
        crossings += inside(q[std::size_t(i)]) != inside(q[std::size_t((i + 1) % 4)]);
      if (crossings == 2) {
        std::array<int, 2> seg{};
        int s = 0;
        Eigen::Vector3d ref = Eigen::Vector3d::Zero();
        int nin = 0;
        for (int i = 0; i < 4; ++i) {
          const int a = q[std::size_t(i)], b = q[std::size_t((i + 1) % 4)];
          if (inside(a) != inside(b)) seg[std::size_t(s++)] = t.edge_of[a][b];
          if (inside(a)) {
            ref += CornerOffset(a);
            ++nin;
          }
        }
        segments.push_back(seg);
        refs.push_back(ref / nin);
      } else if (crossings == 4) {
        // Ambiguous face: cut off each inside corner on its own (inside corners separated).
        for (int i = 0; i < 4; ++i) {
          const int c = q[std::size_t(i)];
          if (!inside(c)) continue;
          const int prev = q[std::size_t((i + 3) % 4)], nxt = q[std::size_t((i + 1) % 4)];
          segments.push_back({t.edge_of[prev][c], t.edge_of[c][nxt]});
          refs.push_back(CornerOffset(c));
        }
      }
      for (std::size_t s = 0; s < segments.size(); ++s) {
        int a = segments[s][0], b = segments[s][1];
        const Eigen::Vector3d pa = midpoint(a), pb = midpoint(b);
        // Inside on the left, seen from outside the cube.
        if ((pb - pa).cross(refs[s] - pa).dot(outward) < 0.0) std::swap(a, b);
        next[std::size_t(a)] = b;
      }
    }
    std::array<bool, 12> used{};
    for (int start = 0; start < 12; ++start) {
      if (next[std::size_t(start)] < 0 || used[std::size_t(start)]) continue;
      std::vector<int> loop;
      for (int x = start; !used[std::size_t(x)]; x = next[std::size_t(x)]) {
        used[std::size_t(x)] = true;
        loop.push_back(x);
      }
      for (std::size_t i = 1; i + 1 < loop.size(); ++i) {
        t.triangles[std::size_t(mask)].push_back(
            {std::int8_t(loop[0]), std::int8_t(loop[i]), std::int8_t(loop[i + 1])});
      }
    }
  }
  // Orientation: with only corner 0 inside, the triangle must face away from it (toward s > 0).
  const auto& tri = t.triangles[1].front();
  const Eigen::Vector3d a = midpoint(tri[0]), b = midpoint(tri[1]), c = midpoint(tri[2]);
  if ((b - a).cross(c - a).dot((a + b + c) / 3.0) < 0.0) {
    for (auto& list : t.triangles)
      for (auto& tr : list) std::swap(tr[1], tr[2]);
  }
  return t;
}

const CaseTable& Table() {
  static const CaseTable table = BuildTable();
  return table;
}

constexpr GridKey kStep[3] = {kGridKeyStepX, kGridKeyStepY, kGridKeyStepZ};

inline GridKey CornerKey(GridKey cube, int c) {
  return cube + ((c & 1) ? kStep[0] : 0) + ((c & 2) ? kStep[1] : 0) + ((c & 4) ? kStep[2] : 0);
}

}  // namespace

bool MarchingCubesOptions::IsValid(std::string* why) const {
  auto fail = [&](const char* text) {
    if (why) *why = text;
    return false;
  };
  if (!(spacing_mm > 0.0) || !std::isfinite(spacing_mm)) return fail("marching cubes spacing must be > 0 mm");
  if (!origin.allFinite()) return fail("marching cubes origin must be finite");
  if (max_cubes < 1) return fail("max cubes must be >= 1");
  return true;
}

MarchingCubesResult ExtractIsosurface(const ScalarField& field, const Points3& seeds,
                                      const MarchingCubesOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) ThrowUsage(why);
  const CaseTable& table = Table();
  const double h = options.spacing_mm;
  MarchingCubesResult result;
  if (seeds.rows() == 0) return result;
  const Bounds3 b = ComputeBounds(seeds);
  CheckGridFits(std::max((b.max - options.origin).cwiseAbs().maxCoeff(),
                         (b.min - options.origin).cwiseAbs().maxCoeff()),
                h, "marching cubes grid");
  // Cubes this near the end of the key range are not left (their neighbours would not pack).
  auto inside_key_range = [](GridKey cube) {
    const auto i = UnpackGridKey(cube);
    return (i.array() > -kGridKeyOffset + 2).all() && (i.array() < kGridKeyOffset - 2).all();
  };

  GridKeyMap<double> values(std::size_t(seeds.rows()) * 2);
  GridKeyMap<char> visited(std::size_t(seeds.rows()) * 2);
  std::vector<GridKey> frontier, surface;
  for (Eigen::Index i = 0; i < seeds.rows(); ++i) {
    const Eigen::Vector3d u = (seeds.row(i).transpose() - options.origin) / h;
    const GridKey key = PackGridKey(std::int64_t(std::floor(u.x())), std::int64_t(std::floor(u.y())),
                                    std::int64_t(std::floor(u.z())));
    if (visited.Insert(key, 1).second) frontier.push_back(key);
  }

  const double nan = std::numeric_limits<double>::quiet_NaN();
  std::vector<GridKey> to_evaluate;
  Points3 points;
  Eigen::VectorXd batch_values;
  while (!frontier.empty()) {
    // Evaluate the corners not known yet, in one batch.
    to_evaluate.clear();
    for (const GridKey cube : frontier)
      for (int c = 0; c < 8; ++c) {
        const GridKey key = CornerKey(cube, c);
        if (values.Insert(key, nan).second) to_evaluate.push_back(key);
      }
    points.resize(Eigen::Index(to_evaluate.size()), 3);
    for (std::size_t i = 0; i < to_evaluate.size(); ++i) {
      points.row(Eigen::Index(i)) =
          (options.origin + UnpackGridKey(to_evaluate[i]).cast<double>() * h).transpose();
    }
    field(points, &batch_values);
    if (batch_values.size() != points.rows())
      ThrowFailure("marching cubes: the field returned the wrong count");
    for (std::size_t i = 0; i < to_evaluate.size(); ++i)
      *values.Find(to_evaluate[i]) = batch_values(Eigen::Index(i));
    result.evaluations += std::int64_t(to_evaluate.size());

    // Keep the cubes the surface crosses; step across every face the surface crosses.
    std::vector<GridKey> next;
    for (const GridKey cube : frontier) {
      double v[8];
      bool defined = true;
      int mask = 0;
      for (int c = 0; c < 8; ++c) {
        v[c] = *values.Find(CornerKey(cube, c));
        defined = defined && std::isfinite(v[c]);
        mask |= (v[c] < 0.0) << c;
      }
      if (!defined) {
        ++result.undefined_cubes;
        continue;
      }
      if (mask == 0 || mask == 255) continue;
      surface.push_back(cube);
      if (!inside_key_range(cube)) continue;
      for (int f = 0; f < 6; ++f) {
        const auto& q = table.faces[std::size_t(f)];
        const int m =
            ((mask >> q[0]) & 1) + ((mask >> q[1]) & 1) + ((mask >> q[2]) & 1) + ((mask >> q[3]) & 1);
        if (m == 0 || m == 4) continue;
        const int axis = f / 2;
        const GridKey neighbour = (f % 2) ? cube + kStep[axis] : cube - kStep[axis];
        if (visited.Insert(neighbour, 1).second) next.push_back(neighbour);
      }
    }
    if (std::int64_t(visited.size()) > options.max_cubes) {
      result.reached_limit = true;
      break;
    }
    frontier.swap(next);
  }
  result.surface_cubes = std::int64_t(surface.size());

  // Triangles, with one vertex per crossed grid edge.
  std::sort(surface.begin(), surface.end());
  GridKeyMap<std::int32_t> vertex_of[3] = {GridKeyMap<std::int32_t>(surface.size()),
                                           GridKeyMap<std::int32_t>(surface.size()),
                                           GridKeyMap<std::int32_t>(surface.size())};
  std::vector<Eigen::Vector3d> vertices;
  std::vector<Eigen::Vector3i> faces;
  vertices.reserve(surface.size() * 2);
  faces.reserve(surface.size() * 2);
  for (const GridKey cube : surface) {
    double v[8];
    int mask = 0;
    for (int c = 0; c < 8; ++c) {
      v[c] = *values.Find(CornerKey(cube, c));
      mask |= (v[c] < 0.0) << c;
    }
    int ids[12];
    std::fill(ids, ids + 12, -1);
    for (const auto& tri : table.triangles[std::size_t(mask)]) {
      Eigen::Vector3i face;
      for (int k = 0; k < 3; ++k) {
        const int e = tri[std::size_t(k)];
        if (ids[e] < 0) {
          const Edge& edge = table.edges[std::size_t(e)];
          const GridKey key = CornerKey(cube, edge.c0);
          auto [slot, inserted] = vertex_of[edge.axis].Insert(key, std::int32_t(vertices.size()));
          if (inserted) {
            const double v0 = v[edge.c0], v1 = v[edge.c1];
            const double s = std::clamp(v0 / (v0 - v1), 1e-3, 1.0 - 1e-3);
            Eigen::Vector3d p = options.origin + UnpackGridKey(key).cast<double>() * h;
            p(edge.axis) += s * h;
            vertices.push_back(p);
          }
          ids[e] = *slot;
        }
        face(k) = ids[e];
      }
      faces.push_back(face);
    }
  }
  result.mesh.vertices.positions.resize(Eigen::Index(vertices.size()), 3);
  for (std::size_t i = 0; i < vertices.size(); ++i)
    result.mesh.vertices.positions.row(Eigen::Index(i)) = vertices[i];
  result.mesh.faces.resize(Eigen::Index(faces.size()), 3);
  for (std::size_t i = 0; i < faces.size(); ++i)
    result.mesh.faces.row(Eigen::Index(i)) = faces[i].transpose();
  return result;
}

}  // namespace pectus
