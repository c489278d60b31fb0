// libFuzzer target: the nodal displacements of a CalculiX .dat file, read from a file held in memory
// (fuzz_file.h). The first byte is the mesh's number of nodes (1-64); the rest is the file. A file read
// without error must give every node a finite displacement.
#include <cstddef>
#include <cstdint>
#include <cstdlib>

#include "planner_plugin/fem/calculix_io.h"
#include "shape/core/error.h"
#include "tests/fuzz/fuzz_file.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  static pectus::fuzz::FuzzFile file(".dat");
  const Eigen::Index num_nodes = 1 + data[0] % 64;
  const auto& path = file.Write(data + 1, size - 1);
  try {
    const pectus::Points3 u = pectus::planner::ReadCalculixDisplacements(path, num_nodes);
    if (!u.allFinite()) std::abort();  // a file read without error lists every node, finite
  } catch (const pectus::Error&) {
  }
  return 0;
}
