// pectus planner: 10-node (quadratic) tetrahedral meshes, their boundary, and linear-to-quadratic lifting.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "shape/core/geometry.h"

namespace pectus::planner {

/// #tets by 4 corner node indices of linear tetrahedra, positively oriented: (x1-x0)x(x2-x0).(x3-x0) > 0.
using Tet4Connectivity = Eigen::Matrix<std::int32_t, Eigen::Dynamic, 4, Eigen::RowMajor>;
/// #tets by 10 node indices of quadratic tetrahedra: the 4 corners, then the mid-edge nodes in the
/// CalculiX C3D10 (Abaqus) order, see kTet10Edges.
using Tet10Connectivity = Eigen::Matrix<std::int32_t, Eigen::Dynamic, 10, Eigen::RowMajor>;
/// #faces by 6 node indices of 6-node boundary triangles: corners 0-2 counter-clockwise seen from
/// outside the solid, then the mid-edge nodes of edges (0,1), (1,2), (2,0).
using Tri6Connectivity = Eigen::Matrix<std::int32_t, Eigen::Dynamic, 6, Eigen::RowMajor>;

/// Corner pairs of the six edges of a tetrahedron; mid-edge node 4 + e lies on edge kTet10Edges[e].
inline constexpr int kTet10Edges[6][2] = {{0, 1}, {1, 2}, {2, 0}, {0, 3}, {1, 3}, {2, 3}};

/// A mesh of 10-node tetrahedra, each in one material region.
struct TetMesh {
  Points3 nodes;            ///< #nodes by 3 positions, mm
  Tet10Connectivity tets;   ///< #tets by 10 node indices
  Eigen::VectorXi regions;  ///< #tets material region indices, >= 0 (index into a material list)

  Eigen::Index num_nodes() const { return nodes.rows(); }
  Eigen::Index num_tets() const { return tets.rows(); }
  /// Throws Error(kBadInput) naming `what` for an index out of range, a negative region, a non-finite
  /// coordinate, or a corner tetrahedron of non-positive volume (naming the element).
  void Validate(const std::string& what) const;
};

/// Lifts a linear mesh to quadratic: one new node at the midpoint of every distinct edge, shared by
/// all tetrahedra around that edge (an edge map), so the quadratic mesh stays conforming.
/// @param[in] nodes    #nodes by 3 corner positions, mm
/// @param[in] tets     #tets by 4 corner indices, positively oriented
/// @param[in] regions  #tets region indices
/// @return the quadratic mesh; its first #nodes nodes are `nodes`, mid-edge nodes follow.
TetMesh MakeQuadratic(const Points3& nodes, const Tet4Connectivity& tets, const Eigen::VectorXi& regions);

/// The boundary of a tetrahedral mesh: every face that belongs to exactly one tetrahedron.
struct MeshBoundary {
  Tri6Connectivity faces;           ///< #faces by 6 node indices, outward orientation
  Eigen::VectorXi face_tet;         ///< #faces owning tetrahedron
  std::vector<std::int32_t> nodes;  ///< sorted indices of every node on the boundary (corners and mid-edge)
};

/// Finds the boundary faces of `mesh`. Throws Error(kFailure) if a face is shared by more than two
/// tetrahedra (a non-manifold, hence broken, mesh).
MeshBoundary ExtractBoundary(const TetMesh& mesh);

/// The boundary faces of a linear tetrahedral mesh: #faces by 3 corner indices, outward, and the owning
/// tetrahedron of each in `face_tet`. Throws Error(kFailure) on a face shared by more than two.
Faces3 ExtractLinearBoundary(const Tet4Connectivity& tets, Eigen::VectorXi* face_tet);

/// The boundary as a linear triangle mesh for display and slicing: each 6-node face is split into its
/// four sub-triangles, so every boundary node is a vertex. Vertices are indexed as in `mesh.nodes`
/// (unused nodes remain as isolated vertices, so per-node fields map one to one).
/// @param[in] positions  #nodes by 3 positions to use (e.g. deformed), mm
TriangleMesh BoundaryTriangles(const MeshBoundary& boundary, const Points3& positions);

/// Quality of the corner tetrahedra: the radius ratio 3 r_in / r_out (1 for a regular tetrahedron,
/// 0 for a flat one), one value per tet.
Eigen::VectorXd RadiusRatios(const TetMesh& mesh);

/// Signed volume of the tetrahedron (a, b, c, d), mm³: positive when (b-a)x(c-a).(d-a) > 0.
double SignedVolume(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                    const Eigen::Vector3d& d);

}  // namespace pectus::planner
