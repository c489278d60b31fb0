#include "registration/estimate_normals.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <memory>
#include <numeric>
#include <queue>
#include <vector>

#include "shape/core/error.h"

namespace pectus {
namespace {

// Undirected graph in compressed rows: the neighbours of i are adjacency[offsets[i] .. offsets[i+1]).
struct Graph {
  std::vector<std::uint32_t> offsets;
  std::vector<std::uint32_t> adjacency;
};

// Symmetrises the directed kNN lists (`knn`, `per_point` entries per point, self excluded).
Graph SymmetricGraph(const std::vector<std::uint32_t>& knn, const std::vector<int>& counts, int per_point) {
  const std::size_t n = counts.size();
  std::vector<std::uint32_t> degree(n, 0);
  for (std::size_t i = 0; i < n; ++i) {
    for (int j = 0; j < counts[i]; ++j) {
      ++degree[i];
      ++degree[knn[i * static_cast<std::size_t>(per_point) + static_cast<std::size_t>(j)]];
    }
  }
  Graph g;
  g.offsets.assign(n + 1, 0);
  for (std::size_t i = 0; i < n; ++i) g.offsets[i + 1] = g.offsets[i] + degree[i];
  g.adjacency.resize(g.offsets[n]);
  std::vector<std::uint32_t> fill(g.offsets.begin(), g.offsets.end() - 1);
  for (std::size_t i = 0; i < n; ++i) {
    for (int j = 0; j < counts[i]; ++j) {
      const std::uint32_t other = knn[i * static_cast<std::size_t>(per_point) + static_cast<std::size_t>(j)];
      g.adjacency[fill[i]++] = other;
      g.adjacency[fill[other]++] = static_cast<std::uint32_t>(i);
    }
  }
  return g;
}

// Hoppe et al. (1992), Sec. 3.3: orient along a minimum spanning tree of the neighbourhood graph with edge
// cost 1 - |n_i . n_j| (Prim's algorithm), so that the sign travels across flat parts first and crosses
// sharp bends last. Each component is seeded at its point farthest from the centroid, made to point away
// from it. Returns the number of components.
std::int64_t OrientByPropagation(const Points3& points, const Graph& graph, Points3* normals) {
  const auto n = static_cast<std::size_t>(points.rows());
  const Eigen::Vector3d centroid = points.colwise().mean().transpose();
  std::vector<std::uint32_t> order(n);
  std::iota(order.begin(), order.end(), 0u);
  std::vector<double> radius(n);
  for (std::size_t i = 0; i < n; ++i) {
    radius[i] = (points.row(static_cast<Eigen::Index>(i)).transpose() - centroid).squaredNorm();
  }
  std::stable_sort(order.begin(), order.end(),
                   [&](std::uint32_t a, std::uint32_t b) { return radius[a] > radius[b]; });

  std::vector<char> done(n, 0);
  using Item = std::pair<double, std::pair<std::uint32_t, std::uint32_t>>;  // cost, (node, parent)
  std::priority_queue<Item, std::vector<Item>, std::greater<Item>> heap;
  std::int64_t components = 0;
  for (const std::uint32_t seed : order) {
    if (done[seed]) continue;
    ++components;
    const auto s = static_cast<Eigen::Index>(seed);
    if (normals->row(s).dot(points.row(s) - centroid.transpose()) < 0.0) normals->row(s) *= -1.0;
    heap.push({0.0, {seed, seed}});
    while (!heap.empty()) {
      const auto [cost, edge] = heap.top();
      heap.pop();
      const auto [node, parent] = edge;
      if (done[node]) continue;
      done[node] = 1;
      const auto i = static_cast<Eigen::Index>(node);
      if (node != parent && normals->row(i).dot(normals->row(static_cast<Eigen::Index>(parent))) < 0.0) {
        normals->row(i) *= -1.0;
      }
      for (std::uint32_t e = graph.offsets[node]; e < graph.offsets[node + 1]; ++e) {
        const std::uint32_t other = graph.adjacency[e];
        if (done[other]) continue;
        const double c = 1.0 - std::abs(normals->row(i).dot(normals->row(static_cast<Eigen::Index>(other))));
        heap.push({c, {other, node}});
      }
    }
  }
  return components;
}

}  // namespace

bool NormalOptions::IsValid(std::string* why) const {
  auto fail = [&](const char* text) {
    if (why) *why = text;
    return false;
  };
  if (k < 3 || k > 256) return fail("k must be in [3, 256]");
  if (!(max_radius_mm >= 0.0) || !std::isfinite(max_radius_mm)) return fail("max_radius_mm must be >= 0");
  if (!viewpoint.allFinite()) return fail("viewpoint must be finite");
  if (orientation == NormalOrientation::kPropagate && (propagation_k < 1 || propagation_k > k)) {
    return fail("propagation_k must be in [1, k]");
  }
  return true;
}

NormalResult EstimateNormals(const Points3& points, const NormalOptions& options, const KdTree3* tree) {
  std::string why;
  if (!options.IsValid(&why)) ThrowUsage("normal estimation: " + why);
  const auto start = std::chrono::steady_clock::now();
  const Eigen::Index n = points.rows();
  std::unique_ptr<KdTree3> own_tree;
  if (tree == nullptr) {
    own_tree = std::make_unique<KdTree3>(points);
    tree = own_tree.get();
  }

  NormalResult result;
  result.normals.setZero(n, 3);
  result.curvature.setZero(n);
  const bool propagate = options.orientation == NormalOrientation::kPropagate;
  const int graph_k = propagate ? options.propagation_k : 0;
  std::vector<std::uint32_t> graph_knn(propagate ? static_cast<std::size_t>(n) * graph_k : 0);
  std::vector<int> graph_counts(propagate ? static_cast<std::size_t>(n) : 0, 0);
  const double max_d2 = options.max_radius_mm > 0.0 ? options.max_radius_mm * options.max_radius_mm
                                                    : std::numeric_limits<double>::infinity();
  std::int64_t degenerate = 0;

#pragma omp parallel reduction(+ : degenerate)
  {
    std::vector<std::uint32_t> idx(static_cast<std::size_t>(options.k));
    std::vector<double> d2(static_cast<std::size_t>(options.k));
#pragma omp for schedule(dynamic, 1024)
    for (Eigen::Index i = 0; i < n; ++i) {
      const Eigen::Vector3d p = points.row(i).transpose();
      int found = tree->Knn(p, options.k, idx.data(), d2.data());
      while (found > 0 && d2[static_cast<std::size_t>(found - 1)] > max_d2) --found;
      if (propagate) {
        // Neighbours for the orientation graph, the point itself excluded.
        int c = 0;
        for (int j = 0; j < found && c < graph_k; ++j) {
          if (idx[static_cast<std::size_t>(j)] == static_cast<std::uint32_t>(i)) continue;
          graph_knn[static_cast<std::size_t>(i) * graph_k + static_cast<std::size_t>(c++)] =
              idx[static_cast<std::size_t>(j)];
        }
        graph_counts[static_cast<std::size_t>(i)] = c;
      }
      if (found < 3) {
        ++degenerate;
        continue;
      }
      // Covariance about the neighbourhood mean (two passes: no cancellation far from the origin).
      Eigen::Vector3d mean = Eigen::Vector3d::Zero();
      for (int j = 0; j < found; ++j)
        mean += points.row(static_cast<Eigen::Index>(idx[static_cast<std::size_t>(j)])).transpose();
      mean /= found;
      Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
      for (int j = 0; j < found; ++j) {
        const Eigen::Vector3d d =
            points.row(static_cast<Eigen::Index>(idx[static_cast<std::size_t>(j)])).transpose() - mean;
        cov.noalias() += d * d.transpose();
      }
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig;
      eig.computeDirect(cov);
      Eigen::Vector3d normal = eig.eigenvectors().col(0);
      const double norm = normal.norm();
      if (!(norm > 0.0) || !normal.allFinite()) {
        ++degenerate;
        continue;
      }
      normal /= norm;
      if (options.orientation == NormalOrientation::kTowardViewpoint &&
          normal.dot(options.viewpoint - p) < 0.0) {
        normal = -normal;
      }
      result.normals.row(i) = normal.transpose();
      const double sum = eig.eigenvalues().sum();
      result.curvature(i) = sum > 0.0 ? std::max(0.0, eig.eigenvalues()(0)) / sum : 0.0;
    }
  }
  result.num_degenerate = degenerate;

  if (propagate && n > 0) {
    const Graph graph = SymmetricGraph(graph_knn, graph_counts, graph_k);
    result.num_components = OrientByPropagation(points, graph, &result.normals);
  }
  result.timings_s.Add("normals",
                       std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  return result;
}

}  // namespace pectus
