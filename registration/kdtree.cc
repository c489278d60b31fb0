// pectus: k-d tree over 3D points (registration/kdtree.h): building nanoflann's tree, on one thread or two.
#include "registration/kdtree.h"

#include <omp.h>

#include <algorithm>
#include <array>
#include <utility>
#include <vector>

namespace pectus {
namespace {

using Index = KdTree3::Index;
using Node = Index::Node;
using BoundingBox = Index::BoundingBox;

// Subtrees of at least this many points, down to this depth, are built as OpenMP tasks in a parallel build.
constexpr std::size_t kMinTaskPoints = 4096;
constexpr int kMaxTaskDepth = 4;

// nanoflann 1.4's divideTree, middleSplit_, computeMinMax and planeSplit (nanoflann.hpp), step for step,
// over `items` (each point's coordinates beside its row) instead of through the index array: the same
// comparisons in the same order, hence the same cuts and the same order of the points. Nodes go into
// `slots`: the subtree over items [left, right) owns the slots [base, base + 2 (right - left) - 1), its
// root the first; a subtree of c points has at most 2c - 1 nodes (both sides of every cut hold a point),
// so the two subtrees of a cut own disjoint slots and are built side by side without locks.
class Builder {
 public:
  struct Item {
    std::array<double, 3> p;
    std::uint32_t row;
  };

  Builder(std::vector<Item> items, std::size_t leaf_size, bool parallel)
      : items_(std::move(items)),
        leaf_size_(leaf_size),
        parallel_(parallel),
        slots_(new Node[2 * items_.size() - 1]) {}

  // The root of the tree over every item; `bbox` holds the items' bounding box on entry.
  Node* Build(BoundingBox* bbox) {
    Node* root = nullptr;
    if (parallel_) {
#pragma omp parallel num_threads(2)
#pragma omp single
      root = Divide(0, items_.size(), bbox, 0, 0);
    } else {
      root = Divide(0, items_.size(), bbox, 0, 0);
    }
    return root;
  }

  const std::vector<Item>& items() const { return items_; }

 private:
  Node* Divide(std::size_t left, std::size_t right, BoundingBox* bbox, int depth, std::size_t base) {
    Node* node = &slots_[base];
    if (right - left <= leaf_size_) {
      node->child1 = node->child2 = nullptr;
      node->node_type.lr.left = left;
      node->node_type.lr.right = right;
      for (int i = 0; i < 3; ++i) (*bbox)[i].low = (*bbox)[i].high = items_[left].p[i];
      for (std::size_t k = left + 1; k < right; ++k) {
        for (int i = 0; i < 3; ++i) {
          if ((*bbox)[i].low > items_[k].p[i]) (*bbox)[i].low = items_[k].p[i];
          if ((*bbox)[i].high < items_[k].p[i]) (*bbox)[i].high = items_[k].p[i];
        }
      }
      return node;
    }
    std::size_t idx = 0;
    int cutfeat = 0;
    double cutval = 0.0;
    MiddleSplit(left, right - left, &idx, &cutfeat, &cutval, *bbox);
    node->node_type.sub.divfeat = cutfeat;
    BoundingBox left_bbox(*bbox);
    left_bbox[cutfeat].high = cutval;
    BoundingBox right_bbox(*bbox);
    right_bbox[cutfeat].low = cutval;
    const std::size_t left_base = base + 1, right_base = base + 2 * idx;
    if (parallel_ && depth < kMaxTaskDepth && right - left >= 2 * kMinTaskPoints) {
#pragma omp task default(shared)
      node->child1 = Divide(left, left + idx, &left_bbox, depth + 1, left_base);
      node->child2 = Divide(left + idx, right, &right_bbox, depth + 1, right_base);
#pragma omp taskwait
    } else {
      node->child1 = Divide(left, left + idx, &left_bbox, depth + 1, left_base);
      node->child2 = Divide(left + idx, right, &right_bbox, depth + 1, right_base);
    }
    node->node_type.sub.divlow = left_bbox[cutfeat].high;
    node->node_type.sub.divhigh = right_bbox[cutfeat].low;
    for (int i = 0; i < 3; ++i) {
      (*bbox)[i].low = std::min(left_bbox[i].low, right_bbox[i].low);
      (*bbox)[i].high = std::max(left_bbox[i].high, right_bbox[i].high);
    }
    return node;
  }

  void MinMax(std::size_t ind, std::size_t count, int element, double* min_elem, double* max_elem) const {
    double lo = items_[ind].p[element], hi = lo;
    for (std::size_t i = 1; i < count; ++i) {
      const double val = items_[ind + i].p[element];
      if (val < lo) lo = val;
      if (val > hi) hi = val;
    }
    *min_elem = lo;
    *max_elem = hi;
  }

  void MiddleSplit(std::size_t ind, std::size_t count, std::size_t* index, int* cutfeat, double* cutval,
                   const BoundingBox& bbox) {
    const auto EPS = static_cast<double>(0.00001);
    double max_span = bbox[0].high - bbox[0].low;
    for (int i = 1; i < 3; ++i) max_span = std::max(max_span, bbox[i].high - bbox[i].low);
    double max_spread = -1;
    *cutfeat = 0;
    std::array<double, 3> lo{}, hi{};
    std::array<bool, 3> known{};
    for (int i = 0; i < 3; ++i) {
      const double span = bbox[i].high - bbox[i].low;
      if (span > (1 - EPS) * max_span) {
        MinMax(ind, count, i, &lo[i], &hi[i]);
        known[i] = true;
        const double spread = hi[i] - lo[i];
        if (spread > max_spread) {
          *cutfeat = i;
          max_spread = spread;
        }
      }
    }
    // The middle of the box, clamped to the points' extent along the cut.
    if (!known[*cutfeat]) MinMax(ind, count, *cutfeat, &lo[*cutfeat], &hi[*cutfeat]);
    const double split_val = (bbox[*cutfeat].low + bbox[*cutfeat].high) / 2;
    const double min_elem = lo[*cutfeat], max_elem = hi[*cutfeat];
    *cutval = split_val < min_elem ? min_elem : split_val > max_elem ? max_elem : split_val;
    std::size_t lim1 = 0, lim2 = 0;
    PlaneSplit(ind, count, *cutfeat, *cutval, &lim1, &lim2);
    if (lim1 > count / 2) {
      *index = lim1;
    } else if (lim2 < count / 2) {
      *index = lim2;
    } else {
      *index = count / 2;
    }
  }

  // Items [ind, ind + lim1) below the cut, [lim1, lim2) on it, the rest above: nanoflann's two passes.
  void PlaneSplit(std::size_t ind, std::size_t count, int cutfeat, double cutval, std::size_t* lim1,
                  std::size_t* lim2) {
    Item* v = items_.data() + ind;
    std::size_t left = 0, right = count - 1;
    for (;;) {
      while (left <= right && v[left].p[cutfeat] < cutval) ++left;
      while (right && left <= right && v[right].p[cutfeat] >= cutval) --right;
      if (left > right || !right) break;
      std::swap(v[left], v[right]);
      ++left;
      --right;
    }
    *lim1 = left;
    right = count - 1;
    for (;;) {
      while (left <= right && v[left].p[cutfeat] <= cutval) ++left;
      while (right && left <= right && v[right].p[cutfeat] > cutval) --right;
      if (left > right || !right) break;
      std::swap(v[left], v[right]);
      ++left;
      --right;
    }
    *lim2 = left;
  }

  std::vector<Item> items_;
  std::size_t leaf_size_;
  bool parallel_;
  std::unique_ptr<Node[]> slots_;
};

// A copy of the subtree at `node` in the index's own node pool, parents before children as nanoflann
// allocates them.
Node* CopyToPool(const Node* node, Index* index) {
  Node* copy = index->pool.template allocate<Node>();
  *copy = *node;
  if (node->child1 != nullptr) {
    copy->child1 = CopyToPool(node->child1, index);
    copy->child2 = CopyToPool(node->child2, index);
  }
  return copy;
}

}  // namespace

KdTree3::KdTree3(const Points3& points, int leaf_size, bool parallel)
    : points_(&points),
      adaptor_(std::make_unique<Adaptor>(Adaptor{&points})),
      index_(std::make_unique<Index>(3, *adaptor_,
                                     nanoflann::KDTreeSingleIndexAdaptorParams(
                                         static_cast<std::size_t>(std::max(leaf_size, 1)),
                                         nanoflann::KDTreeSingleIndexAdaptorFlags::SkipInitialBuildIndex))) {
  Build(std::max(leaf_size, 1), parallel);
}

void KdTree3::Build(int leaf_size, bool parallel) {
  const auto n = static_cast<std::size_t>(points_->rows());
  Index& index = *index_;
  index.freeIndex(index);
  index.m_size = index.m_size_at_index_build = n;
  index.vAcc.resize(n);
  if (n == 0) return;
  std::vector<Builder::Item> items(n);
  for (std::size_t k = 0; k < n; ++k) {
    const auto row = static_cast<Eigen::Index>(k);
    items[k] = {{(*points_)(row, 0), (*points_)(row, 1), (*points_)(row, 2)}, static_cast<std::uint32_t>(k)};
  }
  // nanoflann's computeBoundingBox.
  BoundingBox& bbox = index.root_bbox;
  for (int i = 0; i < 3; ++i) bbox[i].low = bbox[i].high = items[0].p[i];
  for (std::size_t k = 1; k < n; ++k) {
    for (int i = 0; i < 3; ++i) {
      if (items[k].p[i] < bbox[i].low) bbox[i].low = items[k].p[i];
      if (items[k].p[i] > bbox[i].high) bbox[i].high = items[k].p[i];
    }
  }
  // Two threads only where the caller's OpenMP setting allows them (pectus --threads 1 means one).
  const bool two = parallel && n >= 2 * kMinTaskPoints && omp_get_max_threads() >= 2;
  Builder builder(std::move(items), static_cast<std::size_t>(leaf_size), two);
  const Node* root = builder.Build(&bbox);
  for (std::size_t k = 0; k < n; ++k) index.vAcc[k] = builder.items()[k].row;
  index.root_node = CopyToPool(root, &index);
}

KdTree3::~KdTree3() = default;
KdTree3::KdTree3(KdTree3&&) noexcept = default;
KdTree3& KdTree3::operator=(KdTree3&&) noexcept = default;

}  // namespace pectus
