// pectus: is a triangle mesh a manifold without self-intersections? Checked with CGAL's Polygon Mesh
// Processing (the only file of the reconstruction that includes CGAL for this).
#pragma once

#include <cstdint>
#include <string>

#include "shape/core/geometry.h"
#include "shape/core/timings.h"

namespace pectus {

/// What CheckMesh found.
struct MeshCheck {
  /// The faces form an oriented 2-manifold, possibly with border (CGAL
  /// is_polygon_soup_a_polygon_mesh: every edge in at most two faces with opposite directions, every
  /// vertex on one fan). The other fields are only filled when this holds.
  bool manifold = false;
  bool self_intersecting = false;  ///< two faces that share no vertex meet (does_self_intersect)
  bool closed = false;             ///< no border edges (watertight)
  std::int64_t border_edges = 0;   ///< edges with one face
  std::int64_t components = 0;     ///< connected pieces
  double area_mm2 = 0.0;           ///< total area
  Timings timings_s;               ///< "check": wall time (s)
  std::string message;             ///< empty when manifold and not self-intersecting, else why not
};

/// Checks `mesh` with CGAL (exact predicates). Never throws for a bad mesh: the answer says what is
/// wrong. Faces with an index out of range make `manifold` false.
MeshCheck CheckMesh(const TriangleMesh& mesh);

}  // namespace pectus
