// pectus: a surface from a point cloud: oriented normals, a partition-of-unity RBF implicit with
// off-surface constraints, marching cubes on the band the surface passes through, trimming to the data
// with holes filled up to a size, and a manifold check (docs/reconstruction.md).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "shape/core/geometry.h"
#include "shape/core/timings.h"
#include "shape/surface/check_mesh.h"
#include "shape/surface/rbf_implicit.h"
#include "shape/surface/trim_to_data.h"

namespace pectus {

/// Options of ReconstructSurface. Lengths in mm; 0 means "chosen from the data" where said.
struct ReconstructOptions {
  /// Step of the isosurface grid (mm): sets the size of the triangles. 0 = from target_faces if set,
  /// else 1.5 times the point spacing (the side of the square each point covers).
  double spacing_mm = 0.0;
  /// When spacing_mm is 0 and this is > 0: the spacing that gives about this many triangles.
  std::int64_t target_faces = 0;
  /// Spacing of the RBF centres (mm), the finest detail the surface follows. 0 = the largest of twice
  /// the grid step, 4 point spacings (a centre averages several points of a sparse cloud) and 22 noise
  /// levels (it averages the noise): it does not shrink when more points sample the same surface.
  double detail_mm = 0.0;
  /// Bending-energy weight of the local fits (RbfImplicitOptions::smoothing); larger = smoother.
  double smoothing = 1e-3;
  /// Holes up to this width (mm) are filled; wider gaps and everything beyond the edge of an open scan
  /// are trimmed away. 0 fills nothing.
  double fill_holes_mm = 30.0;
  /// Triangles within this distance (mm) of data are kept however they lie. 0 = the RBF centre spacing.
  double margin_mm = 0.0;
  /// Off-surface constraint distance eps (mm). 0 = half the RBF centre spacing.
  double off_surface_distance_mm = 0.0;
  /// Neighbours per point for PCA normals.
  int normal_neighbours = 16;
  /// Estimate normals even if the cloud has them.
  bool recompute_normals = false;
  /// Orient normals toward this scanner position (mm) instead of by propagation.
  std::optional<Eigen::Vector3d> viewpoint;
  /// Check the result with CGAL (manifold, self-intersections); costs about as much as the rest.
  bool check = true;

  /// False, with the reason in `why`, if a value is out of range.
  bool IsValid(std::string* why) const;
};

/// The surface and what it took.
struct ReconstructResult {
  TriangleMesh mesh;                ///< vertices with normals and a "data_distance" scalar (mm)
  RbfFittingAccuracy accuracy;      ///< dissertation Eq. 11 and its parts
  TrimResult trim;                  ///< holes filled, pieces removed
  std::optional<MeshCheck> check;   ///< when options.check
  std::string normals_source;       ///< "input", "propagated" or "viewpoint"
  double point_spacing_mm = 0.0;    ///< side of the square each input point covers (from density)
  double noise_mm = 0.0;            ///< noise level of the points about their surface (NoiseLevel)
  double spacing_mm = 0.0;          ///< grid step used
  double centre_spacing_mm = 0.0;   ///< RBF centre spacing used
  double cell_size_mm = 0.0;        ///< partition-of-unity cell used
  std::int64_t input_points = 0;    ///< points given
  std::int64_t working_points = 0;  ///< points after averaging a dense cloud per cube of detail / 4
  std::int64_t used_points = 0;     ///< working points with a usable normal
  std::int64_t cells = 0;           ///< local fits made (undefined ones included)
  std::int64_t surface_cubes = 0;   ///< marching cubes the surface crossed
  Timings timings_s;                ///< wall time per stage (s), in order
  std::string message;              ///< one line: what was made

  /// One line for a log: the message, then the on-surface residual RMS and 95th percentile (what a user
  /// reads as the error; Carr's maximum stays in `accuracy`) and the wall time.
  std::string BriefReport() const;
};

/// Reconstructs a surface. Throws Error(kBadInput) naming `what` for a cloud that cannot give one
/// (fewer than 16 points, non-finite values, all points on a line, no normals obtainable), and
/// Error(kUsage) for invalid options.
/// @param[in] cloud    #points positions (mm), optionally unit normals pointing out of the object
/// @param[in] options  see ReconstructOptions
/// @param[in] what     name of the cloud in messages (its file)
ReconstructResult ReconstructSurface(const PointCloud& cloud, const ReconstructOptions& options,
                                     const std::string& what = "point cloud");

}  // namespace pectus
