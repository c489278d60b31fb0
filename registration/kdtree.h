// pectus: k-d tree over 3D points (nanoflann), the nearest-neighbour engine of ICP, merging, normals
// and distance maps.
#pragma once

#include <algorithm>
#include <cstdint>
#include <memory>
#include <nanoflann.hpp>
#include <utility>
#include <vector>

#include "shape/core/geometry.h"

namespace pectus {

/// A static k-d tree over the rows of a #points by 3 matrix. The matrix is referenced, not copied: it
/// must outlive the tree and stay unchanged. Queries are const and thread-safe.
///
/// The tree is nanoflann's (its nodes, its searches), built by KdTree3 itself with nanoflann 1.4's rule
/// (the cut in the middle of the box along the axis of widest spread, the points partitioned in
/// place), so that it is the tree nanoflann's own build gives, node for node and in the same point order,
/// hence the same answers. The build works on a contiguous copy of the coordinates, where nanoflann reads
/// every point through its index at every level, and with `parallel` on two OpenMP threads (nanoflann 1.4
/// builds on one): the subtrees below the top cuts are tasks.
class KdTree3 {
 public:
  /// @param[in] points     #points by 3 positions (mm)
  /// @param[in] leaf_size  points per leaf (10 to 20 is fastest for 3D), at least 1
  /// @param[in] parallel   build on two threads (if OpenMP allows two), for a large tree built while the
  ///                       other core is idle
  explicit KdTree3(const Points3& points, int leaf_size = 12, bool parallel = false);
  ~KdTree3();
  KdTree3(const KdTree3&) = delete;
  KdTree3& operator=(const KdTree3&) = delete;
  /// Movable: the nanoflann index lives on the heap with the point set it refers to.
  KdTree3(KdTree3&&) noexcept;
  KdTree3& operator=(KdTree3&&) noexcept;

  Eigen::Index size() const { return points_->rows(); }

  /// The nearest point to `query`: its row and squared distance (mm^2). False if the tree is empty.
  bool Nearest(const Eigen::Vector3d& query, std::uint32_t* index, double* squared_distance) const {
    if (size() == 0) return false;
    nanoflann::KNNResultSet<double, std::uint32_t> result(1);
    result.init(index, squared_distance);
    Search(&result, query, nanoflann::SearchParams(32, 0.0f, false));
    return true;
  }

  /// The nearest point within `max_distance` (mm) of `query`: its row and squared distance (mm^2).
  /// False if there is none. Faster than Nearest() when most queries have no close neighbour, since
  /// branches beyond `max_distance` are never visited.
  bool NearestWithin(const Eigen::Vector3d& query, double max_distance, std::uint32_t* index,
                     double* squared_distance) const {
    if (size() == 0) return false;
    BoundedNearest result(max_distance * max_distance);
    Search(&result, query, nanoflann::SearchParams(32, 0.0f, false));
    if (!result.found) return false;
    *index = result.index;
    *squared_distance = result.best;
    return true;
  }

  /// The two nearest points within `max_distance` (mm) of `query`, closest first: rows into `indices`,
  /// squared distances (mm^2) into `squared_distances`. Returns how many were found (0, 1 or 2). The gap
  /// between the two distances certifies the nearest point: it stays the nearest while the query moves by
  /// less than half the gap (ICP reuses correspondences that way, registration/icp.cc).
  int NearestTwoWithin(const Eigen::Vector3d& query, double max_distance, std::uint32_t indices[2],
                       double squared_distances[2]) const {
    if (size() == 0) return 0;
    BoundedTwoNearest result(max_distance * max_distance);
    Search(&result, query, nanoflann::SearchParams(32, 0.0f, false));
    for (int k = 0; k < result.count; ++k) {
      indices[k] = result.index[k];
      squared_distances[k] = result.dist[k];
    }
    return result.count;
  }

  /// The k <= kMaxBounded nearest points within `max_distance` (mm) of `query`, closest first: rows into
  /// `indices`, squared distances (mm^2) into `squared_distances` (arrays of at least k entries). Returns
  /// how many were found (< k when fewer lie within reach). No allocation.
  static constexpr int kMaxBounded = 8;
  int NearestWithin(const Eigen::Vector3d& query, double max_distance, int k, std::uint32_t* indices,
                    double* squared_distances) const {
    if (size() == 0 || k <= 0) return 0;
    BoundedKNearest result(max_distance * max_distance, std::min(k, kMaxBounded));
    Search(&result, query, nanoflann::SearchParams(32, 0.0f, false));
    for (int j = 0; j < result.count; ++j) {
      indices[j] = result.index[j];
      squared_distances[j] = result.dist[j];
    }
    return result.count;
  }

  /// The k nearest points into caller-owned arrays of at least k entries, closest first; returns how
  /// many were found (< k only when the tree holds fewer than k points). No allocation.
  int Knn(const Eigen::Vector3d& query, int k, std::uint32_t* indices, double* squared_distances) const {
    if (size() == 0 || k <= 0) return 0;
    nanoflann::KNNResultSet<double, std::uint32_t> result(static_cast<std::uint32_t>(k));
    result.init(indices, squared_distances);
    Search(&result, query, nanoflann::SearchParams());
    const int found = static_cast<int>(result.size());
    return found;
  }

  /// The k nearest points, closest first: rows into `indices`, squared distances into
  /// `squared_distances` (both resized to the number found, <= k).
  void Knn(const Eigen::Vector3d& query, int k, std::vector<std::uint32_t>* indices,
           std::vector<double>* squared_distances) const {
    indices->resize(static_cast<std::size_t>(k));
    squared_distances->resize(static_cast<std::size_t>(k));
    if (size() == 0 || k <= 0) {
      indices->clear();
      squared_distances->clear();
      return;
    }
    nanoflann::KNNResultSet<double, std::uint32_t> result(static_cast<std::uint32_t>(k));
    result.init(indices->data(), squared_distances->data());
    Search(&result, query, nanoflann::SearchParams());
    indices->resize(result.size());
    squared_distances->resize(result.size());
  }

  /// Every point within `radius` (mm) of `query`: (row, squared distance) pairs, closest first when
  /// `sorted`. Returns how many.
  std::size_t Radius(const Eigen::Vector3d& query, double radius,
                     std::vector<std::pair<std::uint32_t, double>>* matches, bool sorted = true) const {
    matches->clear();
    if (size() == 0) return 0;
    nanoflann::RadiusResultSet<double, std::uint32_t> result(radius * radius, *matches);
    Search(&result, query, nanoflann::SearchParams(32, 0.0f, sorted));
    if (sorted) std::sort(matches->begin(), matches->end(), nanoflann::IndexDist_Sorter());
    return matches->size();
  }

  /// The rows of a matrix, as nanoflann sees a point set.
  struct Adaptor {
    const Points3* points;
    std::size_t kdtree_get_point_count() const { return static_cast<std::size_t>(points->rows()); }
    double kdtree_get_pt(std::size_t i, std::size_t dim) const {
      return (*points)(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(dim));
    }
    template <class BBox>
    bool kdtree_get_bbox(BBox&) const {
      return false;
    }
  };
  /// The nanoflann index (public for the test that compares the build with nanoflann's own).
  using Index = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<double, Adaptor>, Adaptor, 3,
                                                    std::uint32_t>;
  const Index& index() const { return *index_; }

 private:
  template <class ResultSet>
  void Search(ResultSet* result, const Eigen::Vector3d& query, const nanoflann::SearchParams& params) const {
    index_->findNeighbors(*result, query.data(), params);
  }
  void Build(int leaf_size, bool parallel);

  // A nanoflann result set keeping the single nearest point under a squared-distance bound.
  struct BoundedNearest {
    using DistanceType = double;
    using IndexType = std::uint32_t;
    explicit BoundedNearest(double bound) : best(bound) {}
    bool full() const { return true; }
    bool addPoint(double dist, std::uint32_t i) {
      if (dist < best) {
        best = dist;
        index = i;
        found = true;
      }
      return true;
    }
    double worstDist() const { return best; }
    double best;
    std::uint32_t index = 0;
    bool found = false;
  };
  // A nanoflann result set keeping the two nearest points under a squared-distance bound.
  struct BoundedTwoNearest {
    using DistanceType = double;
    using IndexType = std::uint32_t;
    explicit BoundedTwoNearest(double bound) : bound(bound) {}
    bool full() const { return true; }
    bool addPoint(double d, std::uint32_t i) {
      if (d >= worstDist()) return true;
      if (count == 0 || d < dist[0]) {
        dist[1] = dist[0];
        index[1] = index[0];
        dist[0] = d;
        index[0] = i;
      } else {
        dist[1] = d;
        index[1] = i;
      }
      count = count < 2 ? count + 1 : 2;
      return true;
    }
    double worstDist() const { return count < 2 ? bound : dist[1]; }
    double bound;
    double dist[2] = {0.0, 0.0};
    std::uint32_t index[2] = {0, 0};
    int count = 0;
  };
  // A nanoflann result set keeping the k <= kMaxBounded nearest points under a squared-distance bound,
  // closest first (insertion into a short sorted array).
  struct BoundedKNearest {
    using DistanceType = double;
    using IndexType = std::uint32_t;
    BoundedKNearest(double bound, int capacity) : bound(bound), capacity(capacity) {}
    bool full() const { return true; }
    bool addPoint(double d, std::uint32_t i) {
      if (d >= worstDist()) return true;
      int at = count < capacity ? count++ : capacity - 1;
      for (; at > 0 && dist[at - 1] > d; --at) {
        dist[at] = dist[at - 1];
        index[at] = index[at - 1];
      }
      dist[at] = d;
      index[at] = i;
      return true;
    }
    double worstDist() const { return count < capacity ? bound : dist[capacity - 1]; }
    double bound;
    int capacity;
    double dist[kMaxBounded] = {};
    std::uint32_t index[kMaxBounded] = {};
    int count = 0;
  };
  const Points3* points_;
  // On the heap, so that the index's reference to it survives a move.
  std::unique_ptr<Adaptor> adaptor_;
  std::unique_ptr<Index> index_;
};

}  // namespace pectus
