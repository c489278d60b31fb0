// pectus datasets: a virtual handheld laser scanner (Polhemus FastScan class) sweeping a ChestSurface
// (docs/datasets.md, "The scan").
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "datasets/chest_surface.h"
#include "shape/core/geometry.h"

namespace pectus::datasets {

/// How the scanner is used. Every sweep is a vertical strip of the chest, swept top to bottom with the
/// laser line across it; strips run from the right mid-axillary line to the left one.
struct ScanOptions {
  int sweeps = 5;              ///< number of strips, [1, 12] (3 to 8 is usual)
  double overlap = 0.3;        ///< fraction of a strip's width shared with each neighbour, [0, 0.8]
  double spacing_mm = 1.0;     ///< distance between laser lines and between points on a line, at the
                               ///< strip's centre, (0.2, 20]
  double standoff_mm = 180.0;  ///< distance of the wand from the skin, [50, 500]
  double noise_mm = 0.2;       ///< standard deviation of the range noise along each ray, [0, 5]
  double tracker_deg = 0.5;    ///< rotation error of each sweep's tracker pose (exactly this angle, about
                               ///< a random axis through the wand's mean position), [0, 10]
  double tracker_mm = 1.5;     ///< translation error of each sweep (exactly this length, random
                               ///< direction), [0, 50]
  double breathing_mm = 0.0;   ///< each sweep sees the chest displaced by a breathing field scaled by a
                               ///< draw from [-breathing_mm, breathing_mm] (0: no breathing), [0, 10]
  int subject_holes = 2;       ///< holes missing from every sweep (hair, dark skin), [0, 20]
  int sweep_holes = 1;         ///< holes per sweep (occlusion, specular glare), [0, 20]
  double hole_min_mm = 5.0;    ///< smallest hole diameter, mm
  double hole_max_mm = 40.0;   ///< largest hole diameter, mm (diameters uniform in [min, max])
  double ragged_mm = 6.0;      ///< amplitude of the wander of each strip's side borders, [0, 50]
  double outlier_fraction = 0.003;  ///< fraction of points thrown 5-50 mm along their ray, [0, 0.1]
  double max_incidence_deg = 75.0;  ///< no return beyond this angle between ray and normal, (0, 89]
  double incidence_falloff = 1.0;   ///< a point is kept with probability cos(incidence)^falloff, [0, 10]
  double tremor_mm = 3.0;           ///< hand tremor: smooth wander of the wand's position, [0, 30]
  double tremor_deg = 1.0;          ///< hand tremor: smooth wander of the wand's direction, [0, 10]

  bool IsValid(std::string* why) const;
};

/// A hole in the data: every point of the true surface within diameter / 2 of the centre (3D distance) is
/// missing, from every sweep (sweep = -1) or from one.
struct ScanHole {
  Eigen::Vector2d uv = Eigen::Vector2d::Zero();      ///< surface parameters of the centre
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();  ///< on the true (reference) surface, mm, scan frame
  double diameter_mm = 0.0;
  int sweep = -1;     ///< -1: all sweeps
  std::string cause;  ///< "hair", "dark skin", "occlusion", "glare"
};

/// What is true about one sweep.
struct SweepTruth {
  Rigid3 T_scan_sweep = Rigid3::Identity();  ///< maps the sweep's (tracker) coordinates to the scan frame
  double rotation_error_deg = 0.0;           ///< angle of T_scan_sweep's rotation
  double translation_error_mm = 0.0;         ///< the tracker's translation error
  Eigen::Vector3d pivot = Eigen::Vector3d::Zero();  ///< the wand's mean position (scan frame), the centre of
                                                    ///< the tracker's rotation error
  double breathing_mm = 0.0;  ///< breathing displacement during this sweep (ChestSurface::WithBreathing)
  double strip_u0 = 0.0, strip_u1 = 0.0;  ///< the strip's nominal extent in u
  int lines = 0;                          ///< laser lines swept
  Points3 true_points;   ///< per point, the noise-free surface hit (scan frame, mm); for an outlier,
                         ///< the hit its ray was meant for
  Eigen::VectorXd u, v;  ///< per point, surface parameters of the hit
  std::vector<std::uint8_t> outlier;  ///< per point, 1 for an outlier
};

/// One sweep: its points as the tracker placed them, and the truth.
struct Sweep {
  PointCloud cloud;  ///< positions in the sweep's (tracker) frame, mm; scalars "line" and "column" (laser
                     ///< line and position along it, as a range image)
  SweepTruth truth;
};

/// A whole scan of one subject.
struct Scan {
  std::vector<Sweep> sweeps;
  std::vector<ScanHole> holes;
};

/// Sweeps the surface as a handheld scanner would: per laser line, the wand stands `standoff_mm` off the
/// skin (with tremor) and casts a fan of rays across the strip; each ray is intersected exactly with the
/// surface (of this sweep's breathing state), thinned with the incidence angle, cut by holes, offset by
/// Gaussian noise along the ray, sometimes thrown off as an outlier; finally the whole sweep is moved by
/// the tracker's error, so that its points lie in the tracker's (wrong) frame and T_scan_sweep brings them
/// back. Deterministic for a seed, whatever the number of threads (sweeps run in parallel).
/// @param[in] surface  the subject's skin, in the scan frame
/// @param[in] seed     the scan's seed (each sweep gets its own derived generator)
Scan SimulateScan(const ChestSurface& surface, const ScanOptions& options, std::uint64_t seed);

}  // namespace pectus::datasets
