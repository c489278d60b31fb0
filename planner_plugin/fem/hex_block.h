// pectus planner: structured blocks of hexahedra split into tetrahedra (the ribcage mesher's building
// block, and the meshes of the verification tests).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "planner_plugin/fem/tet_mesh.h"
#include "shape/core/geometry.h"

namespace pectus::planner {

/// A structured block of ns x nu x nv hexahedra whose (ns+1)(nu+1)(nv+1) corner nodes are global node
/// ids: node (s, u, v) is node_ids[(s (nu+1) + u) (nv+1) + v]. Blocks share nodes where they meet.
struct HexBlock {
  int ns = 0, nu = 0, nv = 0;          ///< cells along s, u and v, each >= 1
  std::vector<std::int32_t> node_ids;  ///< (ns+1)(nu+1)(nv+1) global node ids
  std::vector<int> cell_regions;       ///< ns nu nv region indices, cell (s, u, v) at (s nu + u) nv + v

  std::int32_t& node(int s, int u, int v) {
    return node_ids[(static_cast<std::size_t>(s) * (nu + 1) + u) * (nv + 1) + v];
  }
  std::int32_t node(int s, int u, int v) const {
    return node_ids[(static_cast<std::size_t>(s) * (nu + 1) + u) * (nv + 1) + v];
  }
  int& cell_region(int s, int u, int v) {
    return cell_regions[(static_cast<std::size_t>(s) * nu + u) * nv + v];
  }
  int cell_region(int s, int u, int v) const {
    return cell_regions[(static_cast<std::size_t>(s) * nu + u) * nv + v];
  }
  /// Allocates node_ids (all -1) and cell_regions (all `region`).
  void Resize(int cells_s, int cells_u, int cells_v, int region);
};

/// Splits every hexahedron of `block` into 6 tetrahedra along its (0,0,0)-(1,1,1) diagonal (the Kuhn,
/// or Freudenthal, subdivision: one tetrahedron per order of the three axes), and orients each
/// positively. Every quadrilateral face is cut along the diagonal joining its (min, min) and (max, max)
/// index corners, so two blocks sharing a face conform when their indices increase the same way across
/// it. The block's handedness (the sign of det[e_s, e_u, e_v], summed over its cells) fixes the sign
/// every tetrahedron should have; one of the other sign is folded over, i.e. the block is tangled there.
/// @param[in]     block    the block (node ids must be valid indices into `nodes`)
/// @param[in]     nodes    #nodes by 3 positions, mm
/// @param[in,out] tets     tetrahedra appended
/// @param[in,out] regions  their region indices appended
/// @return the number of folded-over (or flat) tetrahedra; 0 for a valid block
int AppendBlockTetrahedra(const HexBlock& block, const Points3& nodes, std::vector<Eigen::Vector4i>* tets,
                          std::vector<int>* regions);

/// A box [0, size_x] x [0, size_y] x [0, size_z] of nx ny nz hexahedra split as above, one region.
/// @param[out] nodes  (nx+1)(ny+1)(nz+1) by 3 positions, mm; node (i, j, k) is (i (ny+1) + j) (nz+1) + k
/// @param[out] tets   6 nx ny nz positively oriented tetrahedra
void MakeBoxTetrahedra(int nx, int ny, int nz, const Eigen::Vector3d& size, Points3* nodes,
                       Tet4Connectivity* tets);

/// Packs appended tetrahedra into a Tet4Connectivity.
Tet4Connectivity ToConnectivity(const std::vector<Eigen::Vector4i>& tets);

}  // namespace pectus::planner
