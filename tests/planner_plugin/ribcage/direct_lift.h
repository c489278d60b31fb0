// Test helper: sternal lifts from a direct solve of their own (Eigen's simplicial LDL^T of the freshly
// assembled stiffness), independent of RibcageFem's CHOLMOD factorisation and of its unit-force
// scaling, to check the forces the model finds.
#pragma once

#include <Eigen/SparseCholesky>
#include <stdexcept>

#include "planner_plugin/fem/assembly.h"
#include "planner_plugin/ribcage/ribcage_fem.h"

namespace pectus::planner::testing {

/// The stiffness of `fem`'s ribcage assembled and factorised again, apart from `fem`.
class DirectLift {
 public:
  explicit DirectLift(const RibcageFem& fem)
      : fem_(fem), partition_(fem.ribcage().mesh.num_nodes(), AllDofsOf(fem.ribcage().fixed_nodes)) {
    const RibcageMaterials& m = fem.options().materials;
    const AssembledStiffness K =
        AssembleStiffness(fem.ribcage().mesh, {m.sternum, m.rib, m.cartilage}, partition_);
    ldlt_.compute(K.K_ff_lower);
    if (ldlt_.info() != Eigen::Success) throw std::runtime_error("direct LDL^T of the stiffness failed");
  }

  /// The anterior lift of the sternum (RibcageFem::SternumLift) under `load`, mm.
  double SternumLift(const BarLoad& load) const {
    const Eigen::VectorXd forces = fem_.NodalForces(load);
    const auto num_free = static_cast<Eigen::Index>(partition_.free.size());
    Eigen::VectorXd f_free(num_free);
    for (Eigen::Index k = 0; k < num_free; ++k) f_free(k) = forces(partition_.free[k]);
    const Eigen::VectorXd u_free = ldlt_.solve(f_free);
    Points3 u = Points3::Zero(fem_.ribcage().mesh.num_nodes(), 3);
    for (Eigen::Index k = 0; k < num_free; ++k) u(partition_.free[k] / 3, partition_.free[k] % 3) = u_free(k);
    return fem_.SternumLift(u);
  }

 private:
  const RibcageFem& fem_;
  DofPartition partition_;
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>, Eigen::Lower> ldlt_;
};

}  // namespace pectus::planner::testing
