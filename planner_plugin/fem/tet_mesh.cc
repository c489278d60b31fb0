#include "planner_plugin/fem/tet_mesh.h"

#include <algorithm>
#include <array>
#include <cmath>

#include "shape/core/error.h"

namespace pectus::planner {
namespace {

// Outward faces of a positively oriented tetrahedron (corner indices).
constexpr int kFaces[4][3] = {{0, 2, 1}, {0, 1, 3}, {1, 2, 3}, {0, 3, 2}};

// Local mid-edge node (4..9) of the edge between corners i and j.
int MidNode(int i, int j) {
  for (int e = 0; e < 6; ++e) {
    if ((kTet10Edges[e][0] == i && kTet10Edges[e][1] == j) ||
        (kTet10Edges[e][0] == j && kTet10Edges[e][1] == i)) {
      return 4 + e;
    }
  }
  return -1;
}

Eigen::Vector3d Row(const Points3& p, std::int32_t i) { return p.row(i).transpose(); }

}  // namespace

double SignedVolume(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                    const Eigen::Vector3d& d) {
  return (b - a).cross(c - a).dot(d - a) / 6.0;
}

void TetMesh::Validate(const std::string& what) const {
  const Eigen::Index n = num_nodes();
  if (regions.size() != num_tets()) {
    ThrowBadInput(what, std::to_string(regions.size()) + " region indices for " + std::to_string(num_tets()) +
                            " tetrahedra");
  }
  for (Eigen::Index i = 0; i < n; ++i) {
    if (!nodes.row(i).allFinite()) ThrowBadInput(what, "node " + std::to_string(i) + " is not finite");
  }
  for (Eigen::Index t = 0; t < num_tets(); ++t) {
    for (int k = 0; k < 10; ++k) {
      if (tets(t, k) < 0 || tets(t, k) >= n) {
        ThrowBadInput(what, "tetrahedron " + std::to_string(t) + " refers to node " +
                                std::to_string(tets(t, k)) + " of " + std::to_string(n));
      }
    }
    if (regions(t) < 0) ThrowBadInput(what, "tetrahedron " + std::to_string(t) + " has a negative region");
    const double v = SignedVolume(Row(nodes, tets(t, 0)), Row(nodes, tets(t, 1)), Row(nodes, tets(t, 2)),
                                  Row(nodes, tets(t, 3)));
    if (!(v > 0.0)) {
      ThrowBadInput(what, "tetrahedron " + std::to_string(t) + " has non-positive volume " +
                              std::to_string(v) + " mm^3 (inverted or flat)");
    }
  }
}

TetMesh MakeQuadratic(const Points3& nodes, const Tet4Connectivity& tets, const Eigen::VectorXi& regions) {
  const Eigen::Index num_tets = tets.rows();
  // Edge map: sort (edge key, slot) pairs so that equal edges are adjacent, then number them.
  std::vector<std::pair<std::uint64_t, std::int64_t>> edges;
  edges.reserve(static_cast<std::size_t>(num_tets) * 6);
  for (Eigen::Index t = 0; t < num_tets; ++t) {
    for (int e = 0; e < 6; ++e) {
      std::uint32_t a = static_cast<std::uint32_t>(tets(t, kTet10Edges[e][0]));
      std::uint32_t b = static_cast<std::uint32_t>(tets(t, kTet10Edges[e][1]));
      if (a > b) std::swap(a, b);
      edges.emplace_back((static_cast<std::uint64_t>(a) << 32) | b, t * 6 + e);
    }
  }
  std::sort(edges.begin(), edges.end());
  TetMesh mesh;
  mesh.tets.resize(num_tets, 10);
  mesh.tets.leftCols<4>() = tets;
  mesh.regions = regions;
  std::vector<Eigen::Vector3d> mids;
  Eigen::Index next = nodes.rows();
  for (std::size_t i = 0; i < edges.size(); ++i) {
    if (i == 0 || edges[i].first != edges[i - 1].first) {
      const auto a = static_cast<std::int32_t>(edges[i].first >> 32);
      const auto b = static_cast<std::int32_t>(edges[i].first & 0xffffffffu);
      mids.push_back(0.5 * (Row(nodes, a) + Row(nodes, b)));
      ++next;
    }
    const std::int64_t slot = edges[i].second;
    mesh.tets(slot / 6, 4 + slot % 6) = static_cast<std::int32_t>(next - 1);
  }
  mesh.nodes.resize(next, 3);
  mesh.nodes.topRows(nodes.rows()) = nodes;
  for (std::size_t i = 0; i < mids.size(); ++i) {
    mesh.nodes.row(nodes.rows() + static_cast<Eigen::Index>(i)) = mids[i].transpose();
  }
  return mesh;
}

namespace {

// Faces that belong to exactly one tetrahedron: (tet, local face) pairs, in a deterministic order.
template <typename Connectivity>
std::vector<std::pair<std::int32_t, int>> SingleFaces(const Connectivity& tets) {
  struct FaceRef {
    std::array<std::int32_t, 3> key;
    std::int32_t tet;
    std::int8_t face;
    bool operator<(const FaceRef& o) const { return key < o.key; }
  };
  std::vector<FaceRef> refs;
  refs.reserve(static_cast<std::size_t>(tets.rows()) * 4);
  for (Eigen::Index t = 0; t < tets.rows(); ++t) {
    for (int f = 0; f < 4; ++f) {
      std::array<std::int32_t, 3> key = {tets(t, kFaces[f][0]), tets(t, kFaces[f][1]), tets(t, kFaces[f][2])};
      std::sort(key.begin(), key.end());
      refs.push_back({key, static_cast<std::int32_t>(t), static_cast<std::int8_t>(f)});
    }
  }
  std::sort(refs.begin(), refs.end());
  std::vector<std::pair<std::int32_t, int>> single;
  for (std::size_t i = 0; i < refs.size();) {
    std::size_t j = i + 1;
    while (j < refs.size() && refs[j].key == refs[i].key) ++j;
    if (j - i > 2) {
      ThrowFailure("tetrahedral mesh is not manifold: a face of tetrahedron " + std::to_string(refs[i].tet) +
                   " is shared by " + std::to_string(j - i) + " tetrahedra");
    }
    if (j - i == 1) single.emplace_back(refs[i].tet, refs[i].face);
    i = j;
  }
  return single;
}

}  // namespace

MeshBoundary ExtractBoundary(const TetMesh& mesh) {
  const auto single = SingleFaces(mesh.tets);
  MeshBoundary boundary;
  boundary.faces.resize(static_cast<Eigen::Index>(single.size()), 6);
  boundary.face_tet.resize(static_cast<Eigen::Index>(single.size()));
  std::vector<std::int32_t> nodes;
  for (std::size_t k = 0; k < single.size(); ++k) {
    const auto [tet, face] = single[k];
    const int* c = kFaces[face];
    const auto row = static_cast<Eigen::Index>(k);
    for (int i = 0; i < 3; ++i) {
      boundary.faces(row, i) = mesh.tets(tet, c[i]);
      boundary.faces(row, 3 + i) = mesh.tets(tet, MidNode(c[i], c[(i + 1) % 3]));
    }
    boundary.face_tet(row) = tet;
    for (int i = 0; i < 6; ++i) nodes.push_back(boundary.faces(row, i));
  }
  std::sort(nodes.begin(), nodes.end());
  nodes.erase(std::unique(nodes.begin(), nodes.end()), nodes.end());
  boundary.nodes = std::move(nodes);
  return boundary;
}

Faces3 ExtractLinearBoundary(const Tet4Connectivity& tets, Eigen::VectorXi* face_tet) {
  const auto single = SingleFaces(tets);
  Faces3 faces(static_cast<Eigen::Index>(single.size()), 3);
  if (face_tet != nullptr) face_tet->resize(static_cast<Eigen::Index>(single.size()));
  for (std::size_t k = 0; k < single.size(); ++k) {
    const auto [tet, face] = single[k];
    const auto row = static_cast<Eigen::Index>(k);
    for (int i = 0; i < 3; ++i) faces(row, i) = tets(tet, kFaces[face][i]);
    if (face_tet != nullptr) (*face_tet)(row) = tet;
  }
  return faces;
}

TriangleMesh BoundaryTriangles(const MeshBoundary& boundary, const Points3& positions) {
  TriangleMesh out;
  out.vertices.positions = positions;
  const Eigen::Index nf = boundary.faces.rows();
  out.faces.resize(4 * nf, 3);
  for (Eigen::Index f = 0; f < nf; ++f) {
    const auto& q = boundary.faces.row(f);
    // Corners c0 c1 c2, mids m01 m12 m20: three corner triangles and the middle one, all outward.
    out.faces.row(4 * f + 0) << q(0), q(3), q(5);
    out.faces.row(4 * f + 1) << q(3), q(1), q(4);
    out.faces.row(4 * f + 2) << q(5), q(4), q(2);
    out.faces.row(4 * f + 3) << q(3), q(4), q(5);
  }
  return out;
}

Eigen::VectorXd RadiusRatios(const TetMesh& mesh) {
  Eigen::VectorXd ratio(mesh.num_tets());
  for (Eigen::Index t = 0; t < mesh.num_tets(); ++t) {
    const Eigen::Vector3d p0 = Row(mesh.nodes, mesh.tets(t, 0));
    const Eigen::Vector3d a = Row(mesh.nodes, mesh.tets(t, 1)) - p0;
    const Eigen::Vector3d b = Row(mesh.nodes, mesh.tets(t, 2)) - p0;
    const Eigen::Vector3d c = Row(mesh.nodes, mesh.tets(t, 3)) - p0;
    const double six_v = std::abs(a.dot(b.cross(c)));
    const double area =
        0.5 * (a.cross(b).norm() + b.cross(c).norm() + c.cross(a).norm() + (b - a).cross(c - a).norm());
    if (six_v <= 0.0 || area <= 0.0) {
      ratio(t) = 0.0;
      continue;
    }
    const double r_in = 0.5 * six_v / area;  // 3 V / A
    const double r_out =
        (a.squaredNorm() * b.cross(c) + b.squaredNorm() * c.cross(a) + c.squaredNorm() * a.cross(b)).norm() /
        (2.0 * six_v);
    ratio(t) = 3.0 * r_in / r_out;
  }
  return ratio;
}

}  // namespace pectus::planner
