// pectus: the equally spaced resampling grid over the ROI, and shape vectors (dissertation Eq. 12).
#pragma once

#include <Eigen/Core>
#include <string>

#include "shape/core/geometry.h"
#include "shape/model/compute_chest_roi.h"

namespace pectus {

/// Vertices of the grid across (lateral) and along (sternal) the chest. The dissertation's mesh of
/// 50 by 100 units is 51 by 101 vertices: m = 5151, a shape vector of 15453 numbers.
struct GridSize {
  int lateral = 51;   ///< vertices across the chest (columns), >= 2
  int sternal = 101;  ///< vertices along the sternal line (rows), >= 2

  Eigen::Index num_vertices() const { return static_cast<Eigen::Index>(lateral) * sternal; }
  /// Vertex index of row i (sternal) and column j (lateral): i * lateral + j.
  Eigen::Index Index(int i, int j) const { return static_cast<Eigen::Index>(i) * lateral + j; }
  /// False, with the reason, unless both counts are in [2, 100000] and the product fits an int32.
  bool IsValid(std::string* why) const;
};

/// Parses "51x101" (lateral x sternal); throws Error(kUsage) otherwise.
GridSize ParseGridSize(const std::string& text);

/// Lateral coordinates u_j (mm) of the grid columns: `size.lateral` values equally spaced over
/// [roi.u_min, roi.u_max].
Eigen::VectorXd GridLateralPositions(const ChestRoi& roi, const GridSize& size);
/// Sternal coordinates v_i (mm) of the grid rows: equally spaced over [roi.v_min, roi.v_max].
Eigen::VectorXd GridSternalPositions(const ChestRoi& roi, const GridSize& size);

/// Two triangles per grid cell, #2(lateral-1)(sternal-1) by 3, wound so that the normals point along
/// the ROI normal (anterior) when the vertices lie at their ROI positions.
Faces3 GridFaces(const GridSize& size);

/// The shape vector (x1, y1, z1, ..., xm, ym, zm) of #m by 3 vertices (mm), Eq. (12).
Eigen::VectorXd ToShapeVector(const Points3& vertices);
/// #m by 3 vertices from a shape vector of 3m numbers; throws Error(kBadInput) if the size is not a
/// multiple of 3.
Points3 FromShapeVector(const Eigen::VectorXd& shape);

}  // namespace pectus
