// pectus: unit normals per vertex of a triangle mesh, each the area-weighted average of the normals of
// the faces around it (the sum of the faces' cross products; libigl's PER_VERTEX_NORMALS_WEIGHTING_AREA).
#pragma once

#include <Eigen/Core>

#include "shape/core/geometry.h"

namespace pectus {

/// Area-weighted unit vertex normals. A face's normal follows its winding (counter-clockwise seen from
/// the side it points to).
/// @param[in] V         #V by 3 vertex positions (mm)
/// @param[in] F         #F by 3 vertex indices (in range; not checked)
/// @param[in] isolated  the normal given to a vertex on no face of positive area
/// @return #V by 3 unit normals (or `isolated`)
Points3 PerVertexNormals(const Points3& V, const Faces3& F,
                         const Eigen::RowVector3d& isolated = Eigen::RowVector3d::Zero());

}  // namespace pectus
