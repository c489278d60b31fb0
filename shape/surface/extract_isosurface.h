// pectus: isosurface s = 0 of a scalar field by marching cubes that follow the surface from seed points
// (continuation: only cubes the surface passes through are visited), with a case table that resolves
// every ambiguous face the same way from both sides, so the mesh is crack-free and manifold.
#pragma once

#include <cstdint>
#include <functional>
#include <string>

#include "shape/core/geometry.h"

namespace pectus {

/// Values of a scalar field at a batch of points: `values` gets one entry per row of `points`, NaN where
/// the field is undefined (the surface stops there). Called with batches of many points at a time.
using ScalarField = std::function<void(const Points3& points, Eigen::VectorXd* values)>;

/// Options of ExtractIsosurface.
struct MarchingCubesOptions {
  double spacing_mm = 1.0;                           ///< grid step (mm), > 0
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();  ///< a grid corner (mm)
  std::int64_t max_cubes = 100'000'000;              ///< stop (reached_limit) after this many cubes

  /// False, with the reason in `why`, if a value is out of range.
  bool IsValid(std::string* why) const;
};

/// The mesh and what it took.
struct MarchingCubesResult {
  TriangleMesh mesh;                 ///< triangles counter-clockwise seen from where s > 0
  std::int64_t surface_cubes = 0;    ///< cubes the surface passes through
  std::int64_t undefined_cubes = 0;  ///< cubes skipped because a corner value was NaN
  std::int64_t evaluations = 0;      ///< grid points evaluated
  bool reached_limit = false;        ///< max_cubes was hit: the surface is incomplete
};

/// Extracts the zero set of `field` connected to the cubes that contain `seeds`.
///
/// Marching cubes (Lorensen and Cline 1987) with a table built from one rule: on a face whose diagonal
/// corners share a sign (the ambiguous face), the negative corners are separated. Both cubes sharing a
/// face apply the same rule, so the surface has no cracks; vertices on grid edges are shared (welded),
/// so every interior edge has exactly two triangles and every vertex one fan. Vertices are kept at
/// least 0.1% of a grid step from grid corners, so no triangle collapses to a point.
/// @param[in] field    the scalar field (negative inside)
/// @param[in] seeds    #seeds by 3 points near the surface (mm)
/// @param[in] options  grid
MarchingCubesResult ExtractIsosurface(const ScalarField& field, const Points3& seeds,
                                      const MarchingCubesOptions& options);

}  // namespace pectus
