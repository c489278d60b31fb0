#include "planner_plugin/fem/hex_block.h"

#include <algorithm>

#include "shape/core/error.h"

namespace pectus::planner {

void HexBlock::Resize(int cells_s, int cells_u, int cells_v, int region) {
  ns = cells_s;
  nu = cells_u;
  nv = cells_v;
  node_ids.assign(static_cast<std::size_t>(ns + 1) * (nu + 1) * (nv + 1), -1);
  cell_regions.assign(static_cast<std::size_t>(ns) * nu * nv, region);
}

int AppendBlockTetrahedra(const HexBlock& block, const Points3& nodes, std::vector<Eigen::Vector4i>* tets,
                          std::vector<int>* regions) {
  // The six orders of the axes (s, u, v) with their parities; a tetrahedron walks from corner (0,0,0)
  // adding one unit step per axis, so its volume is parity * det[e_s, e_u, e_v] / 6 for a parallelepiped.
  static constexpr int kOrders[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
  static constexpr int kParity[6] = {1, -1, -1, 1, 1, -1};
  auto position = [&](int s, int u, int v) -> Eigen::Vector3d {
    return nodes.row(block.node(s, u, v)).transpose();
  };
  double handedness = 0.0;
  for (int s = 0; s < block.ns; ++s) {
    for (int u = 0; u < block.nu; ++u) {
      for (int v = 0; v < block.nv; ++v) {
        if (block.node(s, u, v) < 0 || block.node(s + 1, u, v) < 0 || block.node(s, u + 1, v) < 0 ||
            block.node(s, u, v + 1) < 0) {
          continue;
        }
        const Eigen::Vector3d p = position(s, u, v);
        handedness +=
            (position(s + 1, u, v) - p).cross(position(s, u + 1, v) - p).dot(position(s, u, v + 1) - p);
      }
    }
  }
  const double sign = handedness >= 0 ? 1.0 : -1.0;
  int folded = 0;
  for (int s = 0; s < block.ns; ++s) {
    for (int u = 0; u < block.nu; ++u) {
      for (int v = 0; v < block.nv; ++v) {
        for (int o = 0; o < 6; ++o) {
          int corner[3] = {s, u, v};
          Eigen::Vector4i tet;
          tet(0) = block.node(corner[0], corner[1], corner[2]);
          for (int k = 0; k < 3; ++k) {
            ++corner[kOrders[o][k]];
            tet(k + 1) = block.node(corner[0], corner[1], corner[2]);
          }
          if ((tet.array() < 0).any()) {
            ThrowFailure("hex block: a node of cell (" + std::to_string(s) + ", " + std::to_string(u) + ", " +
                         std::to_string(v) + ") is unset");
          }
          const double expected = sign * kParity[o];
          const double volume = SignedVolume(nodes.row(tet(0)).transpose(), nodes.row(tet(1)).transpose(),
                                             nodes.row(tet(2)).transpose(), nodes.row(tet(3)).transpose());
          if (!(volume * expected > 0.0)) ++folded;
          if (expected < 0.0) std::swap(tet(2), tet(3));
          tets->push_back(tet);
          regions->push_back(block.cell_region(s, u, v));
        }
      }
    }
  }
  return folded;
}

void MakeBoxTetrahedra(int nx, int ny, int nz, const Eigen::Vector3d& size, Points3* nodes,
                       Tet4Connectivity* tets) {
  HexBlock block;
  block.Resize(nx, ny, nz, 0);
  nodes->resize(static_cast<Eigen::Index>(nx + 1) * (ny + 1) * (nz + 1), 3);
  std::int32_t id = 0;
  for (int i = 0; i <= nx; ++i) {
    for (int j = 0; j <= ny; ++j) {
      for (int k = 0; k <= nz; ++k) {
        nodes->row(id) << size(0) * i / nx, size(1) * j / ny, size(2) * k / nz;
        block.node(i, j, k) = id++;
      }
    }
  }
  std::vector<Eigen::Vector4i> list;
  std::vector<int> regions;
  AppendBlockTetrahedra(block, *nodes, &list, &regions);
  *tets = ToConnectivity(list);
}

Tet4Connectivity ToConnectivity(const std::vector<Eigen::Vector4i>& tets) {
  Tet4Connectivity out(static_cast<Eigen::Index>(tets.size()), 4);
  for (std::size_t t = 0; t < tets.size(); ++t) out.row(static_cast<Eigen::Index>(t)) = tets[t].transpose();
  return out;
}

}  // namespace pectus::planner
