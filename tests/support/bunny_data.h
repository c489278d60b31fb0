// The ten Stanford bunny sweeps of ../shared/datasets/stanford_bunny (in mm) and their published bun.conf
// placements, as the merge and reconstruct tests and benchmarks read them.
#pragma once

#include <string>
#include <vector>

#include "shape/core/geometry.h"
#include "shape/io/mesh_io.h"
#include "shape/io/stanford_conf.h"
#include "tests/support/shared_data.h"

namespace pectus::testing_support {

/// The sweeps named in bun.conf, in its order.
struct BunnySweeps {
  std::vector<ScanPose> poses;     ///< bun.conf, translations in mm
  std::vector<PointCloud> sweeps;  ///< each sweep in its own scanner frame (mm)
  std::vector<Rigid3> placements;  ///< T_common_scan of each sweep (mm), bun.conf's placement
};

/// Reads bun.conf and every sweep it names (metres in the files, mm here).
inline BunnySweeps ReadBunnySweeps() {
  BunnySweeps b;
  const std::string dir = BunnyDirectory();
  b.poses = ReadStanfordConf(dir + "bun.conf");
  ScaleTranslations(1000.0, &b.poses);
  ReadOptions ro;
  ro.input_units = LengthUnit::kMetre;
  for (const auto& p : b.poses) {
    b.sweeps.push_back(ReadPointCloud(dir + p.file, ro));
    b.placements.push_back(p.T_common_scan);
  }
  return b;
}

}  // namespace pectus::testing_support
