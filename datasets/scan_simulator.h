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

/// How the points of a laser line are placed.
enum class ScanSampling {
  kGrid,    ///< a range grid: evenly spaced rays along each laser line (a range image, "line" x "column")
  kRandom,  ///< unstructured: points uniformly at random over the swept area, same mean density as kGrid
};
/// How the chest is covered by the sweeps.
enum class SweepPattern {
  kVertical,    ///< vertical strips side by side, each swept top to bottom (the laser line across)
  kHorizontal,  ///< horizontal strips one above the other, each swept across the chest (line vertical)
  kPatches,     ///< a grid of rectangular patches (1 row up to 3 sweeps, 2 rows up to 8, then 3 rows)
  kSpiral,      ///< one path spiralling out from the sternum, each sweep one turn of it
};
/// About which point the tracker's rotation error turns a sweep.
enum class TrackerPivot {
  kWand,   ///< the wand's mean position over the sweep (standoff_mm off the skin, with tremor)
  kLever,  ///< the tracker's sensor: tracker_lever_mm off the sweep's mean skin point along its mean line
           ///< of sight (docs/datasets.md, "The tracker's error")
};
/// How large each sweep's tracker error is.
enum class TrackerDraw {
  kExact,    ///< exactly tracker_deg and tracker_mm (or exactly tracker_skin_mm at the skin)
  kUniform,  ///< each magnitude drawn uniformly in [0, the given value]
};

/// The name of a value as `pectus synth` takes it ("grid", "random"; "vertical", "horizontal", "patches",
/// "spiral"; "wand", "lever"; "exact", "uniform").
std::string ToString(ScanSampling sampling);
std::string ToString(SweepPattern pattern);
std::string ToString(TrackerPivot pivot);
std::string ToString(TrackerDraw draw);
/// The value of a name ToString gives; throws Error(kUsage) listing the names otherwise.
ScanSampling ParseScanSampling(const std::string& text);
SweepPattern ParseSweepPattern(const std::string& text);
TrackerPivot ParseTrackerPivot(const std::string& text);
TrackerDraw ParseTrackerDraw(const std::string& text);

/// How the scanner is used. By default every sweep is a vertical strip of the chest, swept top to bottom
/// with the laser line across it; strips run from the right mid-axillary line to the left one. The
/// defaults of the fields after `tremor_deg` (sampling, pattern, the tracker's pivot, draw and skin
/// displacement) give the scanner as it was before they existed, byte for byte.
struct ScanOptions {
  int sweeps = 5;              ///< number of sweeps, [1, 12] (3 to 8 is usual)
  double overlap = 0.3;        ///< fraction of a sweep's width shared with each neighbour, [0, 0.8]
  double spacing_mm = 1.0;     ///< distance between laser lines and between points on a line, at the
                               ///< strip's centre, (0.2, 20]
  double standoff_mm = 180.0;  ///< distance of the wand from the skin, [50, 500]
  double noise_mm = 0.2;       ///< standard deviation of the range noise along each ray, [0, 5]
  double tracker_deg = 0.5;    ///< rotation error of each sweep's tracker pose (exactly this angle, about
                               ///< a random axis through the pivot, see tracker_pivot), [0, 10]
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

  ScanSampling sampling = ScanSampling::kGrid;       ///< range grid or unstructured points
  SweepPattern pattern = SweepPattern::kVertical;    ///< how the sweeps cover the chest
  TrackerPivot tracker_pivot = TrackerPivot::kWand;  ///< centre of the tracker's rotation error
  double tracker_lever_mm = 200.0;  ///< kLever: the sensor's distance from the skin, mm, [20, 1000]
  TrackerDraw tracker_draw = TrackerDraw::kExact;  ///< exact or uniformly drawn error magnitudes
  /// If > 0: each sweep's error (rotation and translation, in the ratio tracker_deg : tracker_mm) is scaled
  /// so that the RMS displacement of the sweep's true points is exactly this (kExact) or a value drawn
  /// uniformly in [0, this] (kUniform), mm, [0, 50]; 0: tracker_deg and tracker_mm are the magnitudes.
  double tracker_skin_mm = 0.0;

  /// True if every field after tremor_deg has its default (the scanner as it was before they existed).
  bool IsOriginalScanner() const;
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
  Eigen::Vector3d pivot = Eigen::Vector3d::Zero();  ///< the centre of the tracker's rotation error (scan
                                                    ///< frame): the wand's mean position or the sensor's
  double skin_rms_mm = 0.0;   ///< RMS displacement of the sweep's true points by the tracker's error, mm
  double breathing_mm = 0.0;  ///< breathing displacement during this sweep (ChestSurface::WithBreathing)
  double strip_u0 = 0.0, strip_u1 = 0.0;  ///< the sweep's nominal extent in u
  double strip_v0 = 0.0, strip_v1 = 1.0;  ///< ... and in v (a spiral turn: its bounding box)
  int lines = 0;                          ///< laser lines swept (positions of the wand)
  Points3 true_points;   ///< per point, the noise-free surface hit (scan frame, mm); for an outlier,
                         ///< the hit its ray was meant for
  Eigen::VectorXd u, v;  ///< per point, surface parameters of the hit
  std::vector<std::uint8_t> outlier;  ///< per point, 1 for an outlier
};

/// One sweep: its points as the tracker placed them, and the truth.
struct Sweep {
  PointCloud cloud;  ///< positions in the sweep's (tracker) frame, mm; ScanSampling::kGrid: scalars "line"
                     ///< and "column" (laser line and position along it, as a range image); kRandom: none
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
