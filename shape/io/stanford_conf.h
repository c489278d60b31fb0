// pectus: Stanford 3D Scanning Repository alignment files (.conf).
#pragma once

#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "shape/core/geometry.h"

namespace pectus {

/// One `bmesh FILE tx ty tz qx qy qz qw` (or `mesh FILE ...`) line: the pose of a scan in the common frame.
struct ScanPose {
  std::string file;               ///< as written in the .conf (relative to the .conf's folder)
  Rigid3 T_common_scan;           ///< x_common = T_common_scan x_scan, translation in the .conf's units
  std::string keyword = "bmesh";  ///< the line's keyword: "bmesh", or "mesh" (a range scanner's extra part)
};

/// The lines of a .conf. Convention (../shared/datasets/stanford_bunny/SOURCE.md): a point of a scan goes
/// to the common frame as p' = R(q)^T p + t, with R(q) the rotation of the unit quaternion (qx,qy,qz,qw).
/// `bmesh` and `mesh` lines are poses; `camera` lines (the scanning program's viewpoint) are ignored, and
/// so is a `mesh` line that names no file (seven numbers only), with a note. Quaternions are normalised
/// (a zero one is an error). Throws Error(kBadInput) naming the file and line for anything malformed or a
/// file listed twice.
std::vector<ScanPose> ParseStanfordConf(std::string_view bytes, const std::string& name);
/// The same from a file; a `mesh` line whose file is not in the .conf's folder is skipped with a note
/// (several Stanford sets list parts that were not published), a missing `bmesh` file is left to the
/// reader of the scans.
std::vector<ScanPose> ReadStanfordConf(const std::filesystem::path& path);

/// Writes poses atomically in the same convention (so that Read(Write(x)) == x).
void WriteStanfordConf(const std::filesystem::path& path, const std::vector<ScanPose>& poses);

/// Scales the translations (e.g. metres to millimetres).
void ScaleTranslations(double factor, std::vector<ScanPose>* poses);

}  // namespace pectus
