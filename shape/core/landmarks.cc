#include "shape/core/landmarks.h"

#include <set>

#include "shape/core/error.h"

namespace pectus {

const Landmark* LandmarkSet::Find(const std::string& label) const {
  for (const auto& l : items) {
    if (l.label == label) return &l;
  }
  return nullptr;
}

Eigen::Vector3d LandmarkSet::Position(const std::string& label, const std::string& what) const {
  const Landmark* l = Find(label);
  if (l == nullptr) ThrowBadInput(what, "no landmark labelled '" + label + "'");
  return l->position;
}

void LandmarkSet::Validate(const std::string& what) const {
  std::set<std::string> seen;
  for (std::size_t i = 0; i < items.size(); ++i) {
    const Landmark& l = items[i];
    if (l.label.empty()) ThrowBadInput(what, "landmark " + std::to_string(i + 1) + " has no label");
    if (!seen.insert(l.label).second) ThrowBadInput(what, "duplicate landmark label '" + l.label + "'");
    if (!l.position.allFinite()) ThrowBadInput(what, "landmark '" + l.label + "' has a non-finite position");
  }
}

LandmarkSet LandmarkSet::Transformed(const Similarity3& T) const {
  LandmarkSet out = *this;
  for (Landmark& l : out.items) l.position = T * l.position;
  return out;
}

}  // namespace pectus
