// Test helper: an analytic average chest as `pectus resample` lays it out (a grid over the region of
// interest, GridFaces), in the pectus scan frame (x across, y up, z out of the chest): the front of an
// elliptic cylinder, the sternal notch at the top row's middle, the xiphoid at the bottom row's middle.
#pragma once

#include <cmath>

#include "shape/core/geometry.h"
#include "shape/model/shape_grid.h"

namespace pectus::planner::testing {

/// Half-width a and half-depth b of the ellipse (mm); the grid spans |x| <= half_span_mm and
/// y in [-length_mm, 0].
inline TriangleMesh AnalyticChestGrid(int columns = 31, int rows = 41, double a = 150, double b = 110,
                                      double half_span_mm = 90, double length_mm = 170) {
  GridSize size;
  size.lateral = columns;
  size.sternal = rows;
  TriangleMesh mesh;
  mesh.vertices.positions.resize(size.num_vertices(), 3);
  for (int i = 0; i < rows; ++i) {
    for (int j = 0; j < columns; ++j) {
      const double x = -half_span_mm + 2 * half_span_mm * j / (columns - 1);
      const double y = -length_mm * i / (rows - 1);
      mesh.vertices.positions.row(size.Index(i, j)) << x, y, b * std::sqrt(1 - (x / a) * (x / a));
    }
  }
  // GridFaces winds (u, v) so that normals point along the ROI normal = sternal x lateral. Here lateral
  // is +x and sternal (notch to xiphoid) is -y: sternal x lateral = (-y) x (+x) = +z, anterior.
  mesh.faces = GridFaces(size);
  return mesh;
}

}  // namespace pectus::planner::testing
