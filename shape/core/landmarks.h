// pectus: named anatomical landmarks.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "shape/core/geometry.h"

namespace pectus {

/// One named landmark. Position in mm in the pectus frame, which is the frame of the scan it was placed
/// on. Files written by 3D Slicer in RAS are converted to LPS on reading (docs/architecture.md, "Frames").
struct Landmark {
  std::string label;         ///< unique within a set, UTF-8, non-empty
  Eigen::Vector3d position;  ///< mm
  std::string description;   ///< free text, may be empty
};

/// An ordered set of landmarks with unique labels.
struct LandmarkSet {
  std::vector<Landmark> items;

  /// The landmark with this label, or nullptr.
  const Landmark* Find(const std::string& label) const;
  /// The position of the landmark with this label; throws Error(kBadInput) naming `what` if absent.
  Eigen::Vector3d Position(const std::string& label, const std::string& what) const;
  /// Throws Error(kBadInput) naming `what` on an empty or duplicate label or a non-finite position.
  void Validate(const std::string& what) const;
  std::size_t size() const { return items.size(); }
  /// The set moved by T (every position x becomes T x; labels and descriptions kept).
  LandmarkSet Transformed(const Similarity3& T) const;
};

}  // namespace pectus
