// pectus: trim a reconstructed surface to where there was data, keeping the patches that fill holes up
// to a given size, then repair what trimming breaks (small pieces, vertices joining two fans).
#pragma once

#include <cstdint>
#include <string>

#include "registration/kdtree.h"
#include "shape/core/geometry.h"

namespace pectus {

/// Options of TrimToData. Lengths in mm.
struct TrimOptions {
  /// A triangle is "covered" when all its vertices lie within this distance of a data point.
  double margin_mm = 2.0;
  /// A connected region of uncovered triangles that is surrounded by covered ones (it touches no border
  /// of the mesh) is a hole; it is kept (filled) when its width, twice the largest distance from its
  /// vertices to the data, is at most this. Other uncovered regions are removed. 0 fills nothing.
  double max_hole_size_mm = 30.0;
  /// Connected pieces with fewer triangles than this fraction of the largest piece are removed.
  double min_component_fraction = 0.01;

  /// False, with the reason in `why`, if a value is out of range.
  bool IsValid(std::string* why) const;
};

/// What trimming did.
struct TrimResult {
  std::int64_t faces_removed = 0;       ///< uncovered, small pieces and fan repairs together
  std::int64_t holes_filled = 0;        ///< uncovered regions kept as hole fillings
  double largest_hole_filled_mm = 0.0;  ///< width of the widest of them
  std::int64_t holes_left_open = 0;     ///< enclosed uncovered regions wider than max_hole_size_mm
  std::int64_t components_removed = 0;  ///< small pieces removed
  std::int64_t fans_removed = 0;        ///< extra triangle fans removed at non-manifold vertices
  std::int64_t boundary_edges = 0;      ///< edges with one triangle after trimming (0: watertight)
};

/// Trims `mesh` in place. Its vertices get a scalar "data_distance" (mm, distance to the nearest data
/// point); unused vertices are dropped. The mesh must be an edge-manifold triangle mesh (as marching
/// cubes makes); the result is one too, with every vertex on a single fan of triangles.
/// @param[in]     tree     k-d tree over the data points (mm)
/// @param[in,out] mesh     the surface
/// @param[in]     options  margin, hole size, small pieces
TrimResult TrimToData(const KdTree3& tree, TriangleMesh* mesh, const TrimOptions& options);

}  // namespace pectus
