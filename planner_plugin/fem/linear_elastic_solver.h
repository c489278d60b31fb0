// pectus planner: static linear elasticity on a 10-node tetrahedral mesh. Assembles and factorises the
// stiffness once; every load case afterwards is one forward and one backward substitution.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "planner_plugin/fem/assembly.h"
#include "planner_plugin/fem/material.h"
#include "planner_plugin/fem/sparse_cholesky.h"
#include "planner_plugin/fem/tet_mesh.h"
#include "shape/core/geometry.h"
#include "shape/core/timings.h"

namespace pectus::planner {

/// One load case: nodal forces and the values of the prescribed displacements.
struct LoadCase {
  std::string name;  ///< e.g. "position 0.85, 1700 N"
  Eigen::VectorXd
      nodal_forces;  ///< 3 #nodes forces (x, y, z per node), N; forces on prescribed dofs are ignored
  Eigen::VectorXd prescribed_values;  ///< empty (all zero), or one displacement per prescribed dof (ascending
                                      ///< dof order), mm
};

/// Summary of the set-up (assembly and factorisation).
struct LinearElasticSummary {
  Eigen::Index nodes = 0, tets = 0, free_dofs = 0, prescribed_dofs = 0;
  /// Wall time, s: "assembly", then the factorisation's "analyse" and "factorize".
  Timings timings_s;
  SparseCholeskySummary factorization;
  /// One line: sizes and timings.
  std::string BriefReport() const;
};

/// Static linear elasticity K u = f with prescribed displacements eliminated.
class LinearElasticSolver {
 public:
  /// Assembles K over `mesh` (region r uses materials[r]) and factorises its free block.
  /// @param[in] prescribed_dofs  global dofs (3 node + component) whose displacement is given per load
  ///                             case; they must remove every rigid-body motion.
  /// Throws Error as AssembleStiffness and SparseCholesky::Factorize.
  LinearElasticSolver(const TetMesh& mesh, const std::vector<IsotropicMaterial>& materials,
                      std::vector<std::int32_t> prescribed_dofs, const SparseCholeskyOptions& options = {});

  /// Displacements of all nodes (#nodes by 3, mm), one matrix per load case, from a single solve with
  /// every case as a column of the right-hand side. Throws Error(kBadInput) naming the case if a vector
  /// has the wrong size.
  std::vector<Points3> Solve(const std::vector<LoadCase>& cases) const;

  /// Reaction forces at the prescribed dofs for displacements `u` and applied forces `load`:
  /// r_p = K_pf u_f + K_pp u_p - f_p, one value per prescribed dof (ascending), N.
  Eigen::VectorXd Reactions(const Points3& u, const LoadCase& load) const;

  const DofPartition& partition() const { return partition_; }
  const SparseCholesky& factorization() const { return *cholesky_; }
  const LinearElasticSummary& summary() const { return summary_; }

 private:
  Eigen::Index num_nodes_ = 0;
  DofPartition partition_;
  AssembledStiffness stiffness_;
  std::unique_ptr<SparseCholesky> cholesky_;
  LinearElasticSummary summary_;
};

}  // namespace pectus::planner
