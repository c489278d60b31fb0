// pectus: a target surface prepared for ICP (registration/icp.h).
#include <chrono>

#include "registration/icp.h"
#include "registration/voxel_downsample.h"
#include "shape/core/error.h"
#include "shape/core/timings.h"

namespace pectus {

void IcpTarget::Prepare(Points3 positions, const std::string& name) {
  const auto start = std::chrono::steady_clock::now();
  if (positions.rows() < 3) ThrowBadInput(name, "an ICP target needs at least 3 points");
  if (!positions.allFinite()) ThrowBadInput(name, "a position is not finite");
  // Centred on the centroid: a scanner frame 10 km away keeps its sub-micrometre detail in the tree.
  origin_ = positions.colwise().mean().transpose();
  centred_ = std::move(positions);
  centred_.rowwise() -= origin_.transpose();
  tree_ = std::make_unique<KdTree3>(centred_, 12, /*parallel=*/true);  // built on two threads
  spacing_mm_ = MedianPointSpacing(centred_, *tree_);
  timings_s_.Add("prepare", SecondsSince(start));
}

void IcpTarget::SetNormals(Points3 normals, Eigen::Index positions, const std::string& name) {
  if (normals.rows() != positions) {
    ThrowBadInput(name, "has " + std::to_string(positions) + " points but " + std::to_string(normals.rows()) +
                            " normals");
  }
  if (!normals.allFinite()) ThrowBadInput(name, "a normal is not finite");
  normals_ = std::move(normals);
}

IcpTarget::IcpTarget(const Points3& positions, const Points3& normals, const std::string& name) {
  SetNormals(normals, positions.rows(), name);
  Prepare(positions, name);
}

IcpTarget::IcpTarget(Points3&& positions, Points3&& normals, const std::string& name) {
  SetNormals(std::move(normals), positions.rows(), name);
  Prepare(std::move(positions), name);
}

IcpTarget::IcpTarget(const Points3& positions, const NormalOptions& normal_options, const std::string& name) {
  Prepare(positions, name);
  NormalOptions o = normal_options;
  o.viewpoint -= origin_;
  NormalResult normals = EstimateNormals(centred_, o, tree_.get());
  normals_ = std::move(normals.normals);
  timings_s_.Add(normals.timings_s);
}

IcpTarget::~IcpTarget() = default;

}  // namespace pectus
