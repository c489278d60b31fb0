// pectus: validation of the cross-section hole filling (dissertation §5.1, Fig. 44): regions of a scan
// are removed, inside the ROI and across its border, the holed scan is resampled, and the result is
// compared with the resampling of the untouched scan.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "shape/core/geometry.h"
#include "shape/model/compute_chest_roi.h"
#include "shape/model/cross_section_resampler.h"

namespace pectus {

/// A disk-shaped region in the ROI plane (ROI coordinates, mm): everything of the scan whose (u, v)
/// lies within `radius_mm` of (u, v) is removed.
struct RemovedDisk {
  double u = 0.0;           ///< lateral centre, mm
  double v = 0.0;           ///< sternal centre, mm
  double radius_mm = 15.0;  ///< > 0
};

/// Three disks of `radius_mm`: one inside (centre of the ROI), one across the left border at a third of
/// the height, one across the bottom-right corner.
std::vector<RemovedDisk> DefaultRemovedDisks(const ChestRoi& roi, double radius_mm);

/// The scan without the disks: for a mesh, every face with a vertex inside a disk is dropped (and the
/// vertices no face uses); for a point cloud, the points inside. Attributes are kept.
TriangleMesh RemoveDisks(const TriangleMesh& surface, const ChestRoi& roi,
                         const std::vector<RemovedDisk>& disks);

/// What the validation measured.
struct HoleFillResult {
  CrossSectionResult full;     ///< resampling of the untouched scan
  CrossSectionResult holed;    ///< resampling of the scan with the disks removed
  TriangleMesh holed_surface;  ///< the scan with the disks removed
  Eigen::VectorXd error_mm;    ///< per grid vertex: holed minus full depth (signed, mm)
  Eigen::VectorXi in_disk;     ///< per grid vertex: 1 inside a removed disk, 0 elsewhere
  Eigen::Index vertices_in_disks = 0;
  double max_error_in_disks_mm = 0.0;  ///< max |error| over vertices inside the disks
  double rms_error_in_disks_mm = 0.0;
  double max_error_mm = 0.0;  ///< max |error| over the whole grid
  double rms_error_mm = 0.0;
  std::string message;
};

/// Resamples `surface` with and without `disks` (ROI coordinates) and compares the two grids.
/// Throws as ResampleCrossSections; Error(kUsage) for an empty list or a radius <= 0.
HoleFillResult ValidateHoleFill(const TriangleMesh& surface, const ChestRoi& roi,
                                const std::vector<RemovedDisk>& disks,
                                const CrossSectionOptions& options = {}, const std::string& what = "surface");

}  // namespace pectus
