// pectus planner: global stiffness assembly of a 10-node tetrahedral mesh, with prescribed degrees of
// freedom eliminated (the reduced system stays symmetric positive definite).
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <cstdint>
#include <vector>

#include "planner_plugin/fem/material.h"
#include "planner_plugin/fem/tet_mesh.h"

namespace pectus::planner {

/// Degree of freedom d = 3 * node + component (component 0, 1, 2 = x, y, z).
inline std::int32_t Dof(std::int32_t node, int component) { return 3 * node + component; }

/// All three degrees of freedom of each node in `nodes` (sorted, unique), e.g. to clamp them.
std::vector<std::int32_t> AllDofsOf(const std::vector<std::int32_t>& nodes);

/// How the degrees of freedom split into free (solved for) and prescribed (given) ones.
struct DofPartition {
  std::vector<std::int32_t> free;              ///< ascending global dofs that are solved for
  std::vector<std::int32_t> prescribed;        ///< ascending global dofs whose displacement is given
  std::vector<std::int32_t> free_index;        ///< per global dof: index into `free`, or -1
  std::vector<std::int32_t> prescribed_index;  ///< per global dof: index into `prescribed`, or -1

  /// Throws Error(kBadInput) if a prescribed dof is out of range [0, 3 #nodes).
  DofPartition(Eigen::Index num_nodes, std::vector<std::int32_t> prescribed_dofs);
  Eigen::Index num_dofs() const { return static_cast<Eigen::Index>(free_index.size()); }
};

/// The stiffness K split by the partition: K_ff (free rows and columns, lower triangle only, for a
/// Cholesky factorisation), K_fp (free rows, prescribed columns) and K_pp (prescribed rows and columns).
struct AssembledStiffness {
  Eigen::SparseMatrix<double> K_ff_lower;  ///< #free by #free, lower triangle (with diagonal), N/mm
  Eigen::SparseMatrix<double> K_fp;        ///< #free by #prescribed, N/mm
  Eigen::SparseMatrix<double> K_pp;        ///< #prescribed by #prescribed, full, N/mm
};

/// Assembles K = sum_e K_e (Tet10ElementStiffness) into the pattern given by node adjacency, in
/// parallel over elements.
/// @param[in] mesh       quadratic mesh; region r uses materials[r]
/// @param[in] materials  one valid material per region index used by the mesh
/// @param[in] partition  free and prescribed dofs of the mesh's nodes
/// Throws Error(kBadInput) naming the element if one is inverted at a Gauss point, or naming the region
/// if it has no material or an invalid one.
AssembledStiffness AssembleStiffness(const TetMesh& mesh, const std::vector<IsotropicMaterial>& materials,
                                     const DofPartition& partition);

}  // namespace pectus::planner
