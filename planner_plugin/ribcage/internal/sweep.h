// pectus planner: a rectangular cross-section swept along a curve (a rib, a costal cartilage, the
// sternum), giving the node positions of a structured block of hexahedra.
#pragma once

#include <Eigen/Core>
#include <vector>

namespace pectus::planner {

/// One cross-section of a sweep: a height x thickness rectangle centred on the curve, spanned by the
/// unit vectors `up` (height) and `out` (thickness), both perpendicular to the curve.
struct SweepStation {
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();  ///< point on the centre line, mm
  Eigen::Vector3d up = Eigen::Vector3d::UnitZ();     ///< unit, along the height
  Eigen::Vector3d out = Eigen::Vector3d::UnitX();    ///< unit, along the thickness
  double height = 1.0;                               ///< mm
  double thickness = 1.0;                            ///< mm
};

/// Node positions of a sweep as a structured grid: (stations) x (nu + 1) x (nv + 1), node (s, iu, iv) at
/// centre + (iu / nu - 1/2) height up + (iv / nv - 1/2) thickness out, stored at [(s (nu+1) + iu)(nv+1) +
/// iv].
///
/// With `end_window` (nu + 1) x (nv + 1) positions (same index order), the last station is the window
/// itself (where the sweep joins a face of another block), and the offset between the natural last
/// section and the window is blended in over the last `blend_stations` stations (smoothly, zero before),
/// so the elements stay well shaped.
/// @param[in] stations        at least 2
/// @param[in] nu, nv          cells across the height and the thickness, >= 1
/// @param[in] end_window      nullptr, or (nu + 1)(nv + 1) positions, mm
/// @param[in] blend_stations  >= 1
std::vector<Eigen::Vector3d> SweepPositions(const std::vector<SweepStation>& stations, int nu, int nv,
                                            const std::vector<Eigen::Vector3d>* end_window,
                                            int blend_stations);

/// Points along a polyline at equal arc-length spacing: `segments` + 1 points from its first to its
/// last point (segments >= 1).
std::vector<Eigen::Vector3d> ResampleByArcLength(const std::vector<Eigen::Vector3d>& polyline, int segments);

/// Length of a polyline, mm.
double PolylineLength(const std::vector<Eigen::Vector3d>& polyline);

/// Cubic Hermite curve from p0 (tangent t0) to p1 (tangent t1), sampled at `samples` + 1 points.
std::vector<Eigen::Vector3d> HermiteCurve(const Eigen::Vector3d& p0, const Eigen::Vector3d& t0,
                                          const Eigen::Vector3d& p1, const Eigen::Vector3d& t1, int samples);

}  // namespace pectus::planner
