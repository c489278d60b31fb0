#include "planner_plugin/fem/linear_elastic_solver.h"

#include <cstdio>

#include "shape/core/error.h"

namespace pectus::planner {

std::string LinearElasticSummary::BriefReport() const {
  char line[320];
  std::snprintf(
      line, sizeof(line),
      "%lld nodes, %lld tets, %lld free dofs, %lld prescribed; assembly %.2f s, %s: analysis %.2f s, "
      "factorisation %.2f s, nnz(L) %.3g",
      static_cast<long long>(nodes), static_cast<long long>(tets), static_cast<long long>(free_dofs),
      static_cast<long long>(prescribed_dofs), timings_s.Seconds("assembly"), factorization.method.c_str(),
      timings_s.Seconds("analyse"), timings_s.Seconds("factorize"), factorization.nonzeros_factor);
  return line;
}

LinearElasticSolver::LinearElasticSolver(const TetMesh& mesh, const std::vector<IsotropicMaterial>& materials,
                                         std::vector<std::int32_t> prescribed_dofs,
                                         const SparseCholeskyOptions& options)
    : num_nodes_(mesh.num_nodes()), partition_(mesh.num_nodes(), std::move(prescribed_dofs)) {
  {
    auto t = summary_.timings_s.Time("assembly");
    stiffness_ = AssembleStiffness(mesh, materials, partition_);
  }
  cholesky_ = std::make_unique<SparseCholesky>(options);
  cholesky_->Factorize(stiffness_.K_ff_lower);
  summary_.nodes = mesh.num_nodes();
  summary_.tets = mesh.num_tets();
  summary_.free_dofs = static_cast<Eigen::Index>(partition_.free.size());
  summary_.prescribed_dofs = static_cast<Eigen::Index>(partition_.prescribed.size());
  summary_.factorization = cholesky_->summary();
  summary_.timings_s.Add(summary_.factorization.timings_s);
}

std::vector<Points3> LinearElasticSolver::Solve(const std::vector<LoadCase>& cases) const {
  const auto num_free = static_cast<Eigen::Index>(partition_.free.size());
  const auto num_prescribed = static_cast<Eigen::Index>(partition_.prescribed.size());
  const Eigen::Index n = 3 * num_nodes_;
  Eigen::MatrixXd rhs(num_free, static_cast<Eigen::Index>(cases.size()));
  Eigen::MatrixXd prescribed = Eigen::MatrixXd::Zero(num_prescribed, rhs.cols());
  for (std::size_t c = 0; c < cases.size(); ++c) {
    const LoadCase& load = cases[c];
    const auto col = static_cast<Eigen::Index>(c);
    if (load.nodal_forces.size() != n) {
      ThrowBadInput(
          "load case '" + load.name + "'",
          std::to_string(load.nodal_forces.size()) + " force components for " + std::to_string(n) + " dofs");
    }
    if (load.prescribed_values.size() != 0 && load.prescribed_values.size() != num_prescribed) {
      ThrowBadInput("load case '" + load.name + "'", std::to_string(load.prescribed_values.size()) +
                                                         " prescribed values for " +
                                                         std::to_string(num_prescribed) + " prescribed dofs");
    }
    for (Eigen::Index i = 0; i < num_free; ++i) rhs(i, col) = load.nodal_forces(partition_.free[i]);
    if (load.prescribed_values.size() != 0) prescribed.col(col) = load.prescribed_values;
  }
  if (num_prescribed > 0) rhs -= stiffness_.K_fp * prescribed;  // move known displacements to the right
  const Eigen::MatrixXd u_free = cholesky_->Solve(rhs);
  std::vector<Points3> out(cases.size(), Points3::Zero(num_nodes_, 3));
  for (std::size_t c = 0; c < cases.size(); ++c) {
    const auto col = static_cast<Eigen::Index>(c);
    double* u = out[c].data();  // row-major: dof d = 3 node + component is element d
    for (Eigen::Index i = 0; i < num_free; ++i) u[partition_.free[i]] = u_free(i, col);
    for (Eigen::Index i = 0; i < num_prescribed; ++i) u[partition_.prescribed[i]] = prescribed(i, col);
  }
  return out;
}

Eigen::VectorXd LinearElasticSolver::Reactions(const Points3& u, const LoadCase& load) const {
  const auto num_free = static_cast<Eigen::Index>(partition_.free.size());
  const auto num_prescribed = static_cast<Eigen::Index>(partition_.prescribed.size());
  Eigen::VectorXd u_f(num_free), u_p(num_prescribed), f_p(num_prescribed);
  const double* uu = u.data();
  for (Eigen::Index i = 0; i < num_free; ++i) u_f(i) = uu[partition_.free[i]];
  for (Eigen::Index i = 0; i < num_prescribed; ++i) {
    u_p(i) = uu[partition_.prescribed[i]];
    f_p(i) = load.nodal_forces.size() == 0 ? 0.0 : load.nodal_forces(partition_.prescribed[i]);
  }
  return stiffness_.K_fp.transpose() * u_f + stiffness_.K_pp * u_p - f_p;
}

}  // namespace pectus::planner
