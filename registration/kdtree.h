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
/// With `halves` and at least 2 kMinHalfPoints points the tree is built as two: the points are split at the
/// median of their widest axis, copied half by half, and each half gets a nanoflann tree of its own,
/// the two built side by side on two OpenMP threads (nanoflann 1.4 builds on one). A query searches the
/// half on its side of the cut and the other only when the cut is nearer than what it has found: the
/// same answers as one tree (ties in distance apart), whatever the number of threads.
class KdTree3 {
 public:
  /// A tree of fewer points is built whole (the split and the copy would cost more than they save).
  static constexpr Eigen::Index kMinHalfPoints = 32768;

  /// @param[in] points     #points by 3 positions (mm)
  /// @param[in] leaf_size  points per leaf (10 to 20 is fastest for 3D)
  /// @param[in] halves     build two halves side by side (above), for a large tree built while the
  ///                       other core is idle
  explicit KdTree3(const Points3& points, int leaf_size = 12, bool halves = false);
  ~KdTree3();
  KdTree3(const KdTree3&) = delete;
  KdTree3& operator=(const KdTree3&) = delete;
  /// Movable: every nanoflann index lives on the heap with the point set it refers to.
  KdTree3(KdTree3&&) noexcept;
  KdTree3& operator=(KdTree3&&) noexcept;

  Eigen::Index size() const { return points_->rows(); }

  /// The nearest point to `query`: its row and squared distance (mm^2). False if the tree is empty.
  bool Nearest(const Eigen::Vector3d& query, std::uint32_t* index, double* squared_distance) const {
    if (size() == 0) return false;
    nanoflann::KNNResultSet<double, std::uint32_t> result(1);
    result.init(index, squared_distance);
    Search(&result, query, nanoflann::SearchParams(32, 0.0f, false));
    *index = Row(*index);
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
    *index = Row(result.index);
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
      indices[k] = Row(result.index[k]);
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
      indices[j] = Row(result.index[j]);
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
    for (int j = 0; j < found; ++j) indices[j] = Row(indices[j]);
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
    for (std::uint32_t& i : *indices) i = Row(i);
  }

  /// Every point within `radius` (mm) of `query`: (row, squared distance) pairs, closest first when
  /// `sorted`. Returns how many.
  std::size_t Radius(const Eigen::Vector3d& query, double radius,
                     std::vector<std::pair<std::uint32_t, double>>* matches, bool sorted = true) const {
    matches->clear();
    if (size() == 0) return 0;
    nanoflann::RadiusResultSet<double, std::uint32_t> result(radius * radius, *matches);
    Search(&result, query, nanoflann::SearchParams(32, 0.0f, sorted));
    for (auto& m : *matches) m.first = Row(m.first);
    if (sorted) std::sort(matches->begin(), matches->end(), nanoflann::IndexDist_Sorter());
    return matches->size();
  }

 private:
  // Rows [begin, begin + count) of a matrix, as nanoflann sees a point set.
  struct Adaptor {
    const Points3* points;
    Eigen::Index begin;
    Eigen::Index count;
    std::size_t kdtree_get_point_count() const { return static_cast<std::size_t>(count); }
    double kdtree_get_pt(std::size_t i, std::size_t dim) const {
      return (*points)(begin + static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(dim));
    }
    template <class BBox>
    bool kdtree_get_bbox(BBox&) const {
      return false;
    }
  };
  using Index = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<double, Adaptor>, Adaptor, 3,
                                                    std::uint32_t>;
  // One tree over one part of the points (all of them, or a half). Built at once unless `build` is false.
  struct Part {
    Part(const Points3* points, Eigen::Index begin, Eigen::Index count, int leaf_size, bool build = true)
        : adaptor{points, begin, count},
          index(std::make_unique<Index>(3, adaptor, nanoflann::KDTreeSingleIndexAdaptorParams(leaf_size))) {
      if (build && count > 0) index->buildIndex();
    }
    Part(const Part&) = delete;  // the index refers to `adaptor`
    Part& operator=(const Part&) = delete;
    Adaptor adaptor;
    std::unique_ptr<Index> index;
  };
  // Passes a part's results on to a result set with the part's offset added to each index.
  template <class ResultSet>
  struct Shifted {
    ResultSet* result;
    std::uint32_t offset;
    bool full() const { return result->full(); }
    double worstDist() const { return result->worstDist(); }
    bool addPoint(double d, std::uint32_t i) { return result->addPoint(d, i + offset); }
  };
  // Searches the part on the query's side of the cut, then the other if the cut is within reach.
  template <class ResultSet>
  void Search(ResultSet* result, const Eigen::Vector3d& query, const nanoflann::SearchParams& params) const {
    if (parts_.size() == 1) {
      parts_[0]->index->findNeighbors(*result, query.data(), params);
      return;
    }
    const double off = query(axis_) - cut_;
    const std::size_t near = off < 0.0 ? 0 : 1;  // the first half lies below the cut, the second not
    for (const std::size_t k : {near, 1 - near}) {
      if (k != near && off * off > result->worstDist()) break;
      Shifted<ResultSet> shifted{result, static_cast<std::uint32_t>(parts_[k]->adaptor.begin)};
      parts_[k]->index->findNeighbors(shifted, query.data(), params);
    }
  }
  // The row of `points` of an index found by Search.
  std::uint32_t Row(std::uint32_t i) const { return rows_.empty() ? i : rows_[i]; }

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
  std::vector<std::unique_ptr<Part>> parts_;
  // Two halves: their points in order (`ordered_`), the row of `points_` of each (`rows_`), and the cut.
  std::unique_ptr<Points3> ordered_;
  std::vector<std::uint32_t> rows_;
  Eigen::Index axis_ = 0;
  double cut_ = 0.0;
};

}  // namespace pectus
