// pectus: a target surface prepared for ICP (registration/icp.h).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <optional>

#include "registration/icp.h"
#include "registration/internal/icp_steps.h"
#include "registration/internal/radius_grid.h"
#include "registration/random_sample.h"
#include "registration/voxel_downsample.h"
#include "shape/core/error.h"
#include "shape/core/timings.h"

namespace pectus {

namespace {

// The median spacing of `points` as MedianPointSpacing(points, tree) gives it, from a grid instead of a
// tree over every point: each picked point's nearest neighbour is searched within the grid's cell, so it
// is exact where it lies within a cell and known to be farther otherwise; the median is exact while more
// than half are found. Empty otherwise.
std::optional<double> GridMedianSpacing(const Points3& points, const icp_detail::RadiusGrid& grid) {
  const double median = MedianOverPickedRows(points.rows(), kSpacingSamples, [&](Eigen::Index i) {
    std::uint32_t idx[2];
    double d2[2];
    const int found = grid.NearestWithin(points.row(i).transpose(), grid.max_radius(), 2, idx, d2);
    return found == 2 ? std::sqrt(d2[1]) : std::numeric_limits<double>::infinity();
  });
  if (!std::isfinite(median)) return std::nullopt;
  return median;
}

}  // namespace

void IcpTarget::Prepare(Points3 positions, const std::string& name, TargetUse use) {
  const auto start = std::chrono::steady_clock::now();
  if (positions.rows() < 3) ThrowBadInput(name, "an ICP target needs at least 3 points");
  if (!positions.allFinite()) ThrowBadInput(name, "a position is not finite");
  // Centred on the centroid: a scanner frame 10 km away keeps its sub-micrometre detail in the tree.
  origin_ = positions.colwise().mean().transpose();
  centred_ = std::move(positions);
  centred_.rowwise() -= origin_.transpose();
  if (use == TargetUse::kSingleAlignment && centred_.rows() >= CoarseTarget::kMinPoints) PrepareCoarse();
  if (coarse_ == nullptr || !(spacing_mm_ > 0.0)) spacing_mm_ = MedianPointSpacing(centred_, tree());
  timings_s_.Add("prepare", SecondsSince(start));
}

// The coarse sample and its tree, and the spacing of every point from a grid (docs/registration.md, "A
// coarse target for one alignment"). Leaves spacing_mm_ at 0 when the grid cannot give it.
void IcpTarget::PrepareCoarse() {
  // A quarter of the rows, each kept on a hash of its row (deterministic, in row order: a scan's
  // neighbours stay near in memory), so it costs one pass.
  auto coarse = std::make_unique<CoarseTarget>();
  const auto n = static_cast<std::uint32_t>(centred_.rows());
  coarse->rows.reserve(n / 4 + n / 64 + 16);
  for (std::uint32_t row = 0; row < n; ++row) {
    if ((SplitMix64(row) >> 62) == 0) coarse->rows.push_back(row);
  }
  coarse->positions.resize(static_cast<Eigen::Index>(coarse->rows.size()), 3);
  for (std::size_t k = 0; k < coarse->rows.size(); ++k) {
    coarse->positions.row(static_cast<Eigen::Index>(k)) = centred_.row(coarse->rows[k]);
  }
  coarse->tree = std::make_unique<KdTree3>(coarse->positions, 12);  // small: one thread
  coarse->spacing_mm = MedianPointSpacing(coarse->positions, *coarse->tree);
  // A sample of a quarter is sparser than the whole: a cell of twice its spacing holds every point's
  // nearest neighbour but where the points are sparse. A surface fills few of its box's cells: the cell
  // grows until the box needs at most the grid's cells per point (256 searches, whatever the cell).
  if (coarse->spacing_mm > 0.0) {
    const std::size_t max_cells =
        icp_detail::kGridMaxCellsPerPoint * static_cast<std::size_t>(centred_.rows()) + 4096;
    const Eigen::Vector3d extent = centred_.colwise().maxCoeff() - centred_.colwise().minCoeff();
    double cell = 2.0 * coarse->spacing_mm;
    while ((extent / cell + Eigen::Vector3d::Ones()).prod() > 0.5 * static_cast<double>(max_cells))
      cell *= 1.25;
    const std::optional<icp_detail::RadiusGrid> grid =
        icp_detail::RadiusGrid::Build(centred_, cell, max_cells);
    if (grid) spacing_mm_ = GridMedianSpacing(centred_, *grid).value_or(0.0);
  }
  coarse_ = std::move(coarse);
}

const KdTree3& IcpTarget::tree() const {
  std::call_once(tree_once_, [this] {
    if (tree_ == nullptr) tree_ = std::make_unique<KdTree3>(centred_, 12, /*parallel=*/true);  // two threads
  });
  return *tree_;
}

void IcpTarget::SetNormals(Points3 normals, Eigen::Index positions, const std::string& name) {
  if (normals.rows() != positions) {
    ThrowBadInput(name, "has " + std::to_string(positions) + " points but " + std::to_string(normals.rows()) +
                            " normals");
  }
  if (!normals.allFinite()) ThrowBadInput(name, "a normal is not finite");
  normals_ = std::move(normals);
}

IcpTarget::IcpTarget(const Points3& positions, const Points3& normals, const std::string& name,
                     TargetUse use) {
  SetNormals(normals, positions.rows(), name);
  Prepare(positions, name, use);
}

IcpTarget::IcpTarget(Points3&& positions, Points3&& normals, const std::string& name, TargetUse use) {
  SetNormals(std::move(normals), positions.rows(), name);
  Prepare(std::move(positions), name, use);
}

IcpTarget::IcpTarget(const Points3& positions, const NormalOptions& normal_options, const std::string& name) {
  Prepare(positions, name);
  NormalOptions o = normal_options;
  o.viewpoint -= origin_;
  NormalResult normals = EstimateNormals(centred_, o, &tree());
  normals_ = std::move(normals.normals);
  timings_s_.Add(normals.timings_s);
}

IcpTarget::~IcpTarget() = default;

}  // namespace pectus
