#include "planner_plugin/fem/assembly.h"

#include <algorithm>
#include <atomic>
#include <string>

#include "planner_plugin/fem/tet10_element.h"
#include "shape/core/error.h"

namespace pectus::planner {

std::vector<std::int32_t> AllDofsOf(const std::vector<std::int32_t>& nodes) {
  std::vector<std::int32_t> dofs;
  dofs.reserve(nodes.size() * 3);
  for (std::int32_t n : nodes) {
    for (int c = 0; c < 3; ++c) dofs.push_back(Dof(n, c));
  }
  std::sort(dofs.begin(), dofs.end());
  dofs.erase(std::unique(dofs.begin(), dofs.end()), dofs.end());
  return dofs;
}

DofPartition::DofPartition(Eigen::Index num_nodes, std::vector<std::int32_t> prescribed_dofs) {
  const auto n = static_cast<std::int32_t>(3 * num_nodes);
  std::sort(prescribed_dofs.begin(), prescribed_dofs.end());
  prescribed_dofs.erase(std::unique(prescribed_dofs.begin(), prescribed_dofs.end()), prescribed_dofs.end());
  if (!prescribed_dofs.empty() && (prescribed_dofs.front() < 0 || prescribed_dofs.back() >= n)) {
    ThrowBadInput("boundary conditions", "a prescribed degree of freedom lies outside [0, " +
                                             std::to_string(n) + ") for " + std::to_string(num_nodes) +
                                             " nodes");
  }
  prescribed = std::move(prescribed_dofs);
  free_index.assign(static_cast<std::size_t>(n), -1);
  prescribed_index.assign(static_cast<std::size_t>(n), -1);
  for (std::size_t k = 0; k < prescribed.size(); ++k)
    prescribed_index[prescribed[k]] = static_cast<std::int32_t>(k);
  for (std::int32_t d = 0; d < n; ++d) {
    if (prescribed_index[d] < 0) {
      free_index[d] = static_cast<std::int32_t>(free.size());
      free.push_back(d);
    }
  }
}

namespace {

// Sorted neighbour lists (including the node itself) of the node graph of the mesh, as CSR.
void NodeAdjacency(const TetMesh& mesh, std::vector<std::int64_t>* offsets,
                   std::vector<std::int32_t>* neighbours) {
  const Eigen::Index n = mesh.num_nodes();
  std::vector<std::vector<std::int32_t>> lists(static_cast<std::size_t>(n));
  for (Eigen::Index t = 0; t < mesh.num_tets(); ++t) {
    for (int a = 0; a < 10; ++a) {
      auto& list = lists[mesh.tets(t, a)];
      for (int b = 0; b < 10; ++b) list.push_back(mesh.tets(t, b));
    }
  }
  offsets->assign(static_cast<std::size_t>(n) + 1, 0);
  neighbours->clear();
  for (Eigen::Index i = 0; i < n; ++i) {
    auto& list = lists[i];
    list.push_back(static_cast<std::int32_t>(i));
    std::sort(list.begin(), list.end());
    list.erase(std::unique(list.begin(), list.end()), list.end());
    neighbours->insert(neighbours->end(), list.begin(), list.end());
    (*offsets)[i + 1] = static_cast<std::int64_t>(neighbours->size());
    std::vector<std::int32_t>().swap(list);
  }
}

}  // namespace

AssembledStiffness AssembleStiffness(const TetMesh& mesh, const std::vector<IsotropicMaterial>& materials,
                                     const DofPartition& partition) {
  if (partition.num_dofs() != 3 * mesh.num_nodes()) {
    ThrowBadInput("boundary conditions", "degree-of-freedom partition is for " +
                                             std::to_string(partition.num_dofs() / 3) + " nodes, mesh has " +
                                             std::to_string(mesh.num_nodes()));
  }
  std::vector<ElasticityMatrix> D(materials.size());
  for (std::size_t r = 0; r < materials.size(); ++r) {
    std::string why;
    if (!materials[r].IsValid(&why)) ThrowBadInput("materials", "region " + std::to_string(r) + ": " + why);
    D[r] = materials[r].Elasticity();
  }
  for (Eigen::Index t = 0; t < mesh.num_tets(); ++t) {
    if (mesh.regions(t) < 0 || static_cast<std::size_t>(mesh.regions(t)) >= materials.size()) {
      ThrowBadInput("materials", "tetrahedron " + std::to_string(t) + " is in region " +
                                     std::to_string(mesh.regions(t)) + " but only " +
                                     std::to_string(materials.size()) + " materials are given");
    }
  }

  // Pattern of the lower triangle of K_ff (CSC): column j = free dof, rows = free dofs >= j coupled to it.
  std::vector<std::int64_t> adj_offsets;
  std::vector<std::int32_t> adj;
  NodeAdjacency(mesh, &adj_offsets, &adj);
  const auto num_free = static_cast<Eigen::Index>(partition.free.size());
  std::vector<int> outer(static_cast<std::size_t>(num_free) + 1, 0);
  std::vector<int> inner;
  inner.reserve(adj.size() * 5);
  for (Eigen::Index j = 0; j < num_free; ++j) {
    const std::int32_t dof_j = partition.free[j];
    const std::int32_t node = dof_j / 3;
    for (std::int64_t k = adj_offsets[node]; k < adj_offsets[node + 1]; ++k) {
      for (int c = 0; c < 3; ++c) {
        const std::int32_t dof_i = Dof(adj[k], c);
        const std::int32_t i = partition.free_index[dof_i];
        if (i >= j) inner.push_back(i);
      }
    }
    outer[j + 1] = static_cast<int>(inner.size());
  }
  std::vector<std::int64_t>().swap(adj_offsets);
  std::vector<std::int32_t>().swap(adj);
  std::vector<double> values(inner.size(), 0.0);

  using Triplet = Eigen::Triplet<double>;
  std::vector<std::vector<Triplet>> fp_parts, pp_parts;
  std::atomic<Eigen::Index> bad_element{-1};
#pragma omp parallel
  {
    std::vector<Triplet> fp, pp;
    Tet10Nodes X;
    Tet10Stiffness K;
#pragma omp for schedule(static)
    for (Eigen::Index t = 0; t < mesh.num_tets(); ++t) {
      for (int a = 0; a < 10; ++a) X.row(a) = mesh.nodes.row(mesh.tets(t, a));
      if (!Tet10ElementStiffness(X, D[mesh.regions(t)], &K)) {
        bad_element = t;
        continue;
      }
      std::int32_t g[30];
      for (int a = 0; a < 10; ++a) {
        for (int c = 0; c < 3; ++c) g[3 * a + c] = Dof(mesh.tets(t, a), c);
      }
      for (int b = 0; b < 30; ++b) {
        const std::int32_t jf = partition.free_index[g[b]];
        const std::int32_t jp = partition.prescribed_index[g[b]];
        for (int a = 0; a < 30; ++a) {
          const std::int32_t i_f = partition.free_index[g[a]];
          if (i_f >= 0 && jf >= 0) {
            if (i_f < jf) continue;
            const int* begin = inner.data() + outer[jf];
            const int* end = inner.data() + outer[jf + 1];
            const int* pos = std::lower_bound(begin, end, i_f);
            double& v = values[static_cast<std::size_t>(pos - inner.data())];
#pragma omp atomic
            v += K(a, b);
          } else if (i_f >= 0 && jp >= 0) {
            fp.emplace_back(i_f, jp, K(a, b));
          } else if (i_f < 0 && jp >= 0) {
            pp.emplace_back(partition.prescribed_index[g[a]], jp, K(a, b));
          }
        }
      }
    }
#pragma omp critical
    {
      fp_parts.push_back(std::move(fp));
      pp_parts.push_back(std::move(pp));
    }
  }
  if (bad_element >= 0) {
    ThrowBadInput("mesh", "tetrahedron " + std::to_string(bad_element.load()) +
                              " is inverted or flat at a Gauss point (non-positive Jacobian)");
  }

  AssembledStiffness out;
  out.K_ff_lower = Eigen::Map<const Eigen::SparseMatrix<double>>(
      num_free, num_free, static_cast<Eigen::Index>(inner.size()), outer.data(), inner.data(), values.data());
  const auto num_prescribed = static_cast<Eigen::Index>(partition.prescribed.size());
  std::vector<Triplet> all;
  for (auto& part : fp_parts) all.insert(all.end(), part.begin(), part.end());
  out.K_fp.resize(num_free, num_prescribed);
  out.K_fp.setFromTriplets(all.begin(), all.end());
  all.clear();
  for (auto& part : pp_parts) all.insert(all.end(), part.begin(), part.end());
  out.K_pp.resize(num_prescribed, num_prescribed);
  out.K_pp.setFromTriplets(all.begin(), all.end());
  return out;
}

}  // namespace pectus::planner
