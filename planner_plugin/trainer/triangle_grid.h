// pectus trainer: a uniform grid over a triangle soup, the collision structure of the haptic proxy
// (first hit of a segment, nearest point within a radius). Queries allocate nothing and never throw, so
// the 1 kHz servo tick can call them.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "shape/core/geometry.h"

namespace pectus::trainer {

/// Where a query met the surface.
struct SurfaceHit {
  Eigen::Vector3d point = Eigen::Vector3d::Zero();   ///< on the triangle, mm
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();  ///< the triangle's unit outward normal
  double t = 0;                                      ///< segment parameter in [0, 1] (FirstHit)
  double distance_mm = 0;                            ///< from the query point (Nearest)
  std::int32_t face = -1;
};

/// Triangles (#faces by 3 into #vertices by 3, outward) binned into cubic cells by their bounding boxes.
class TriangleGrid {
 public:
  TriangleGrid() = default;
  /// Bins `faces` over `vertices` in cells of `cell_mm` (> 0; 4-8 mm suits organs and bones).
  TriangleGrid(const Points3& vertices, const Faces3& faces, double cell_mm);

  /// The first triangle that the segment a -> b enters from its front (outward) side, skipping the
  /// faces in ignore[0 .. num_ignore). False if none.
  bool FirstHit(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const std::int32_t* ignore,
                int num_ignore, SurfaceHit* hit) const noexcept;
  /// The nearest point of any triangle within `radius_mm` of p. False if none.
  bool Nearest(const Eigen::Vector3d& p, double radius_mm, SurfaceHit* hit) const noexcept;
  /// Every triangle's crossing of the line a -> b (both orientations), t ascending, appended to `hits`.
  /// For building scenes, not for the servo tick (it allocates).
  void AllHits(const Eigen::Vector3d& a, const Eigen::Vector3d& b, std::vector<SurfaceHit>* hits) const;

  const Points3& vertices() const { return vertices_; }
  const Faces3& faces() const { return faces_; }
  const Points3& face_normals() const { return normals_; }

 private:
  Points3 vertices_;
  Faces3 faces_;
  Points3 normals_;
  Eigen::Vector3d origin_ = Eigen::Vector3d::Zero();
  double cell_mm_ = 1;
  Eigen::Vector3i dims_ = Eigen::Vector3i::Ones();
  std::vector<std::int32_t> cell_start_;  // #cells + 1 offsets into cell_faces_
  std::vector<std::int32_t> cell_faces_;

  Eigen::Vector3i CellOf(const Eigen::Vector3d& p) const noexcept;
  /// Calls visit(face) for every face binned in the cells overlapping [lo, hi]; stops when it returns false.
  template <class Visit>
  void ForCells(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, Visit&& visit) const noexcept;
};

}  // namespace pectus::trainer
