// libFuzzer target: PCD files (ascii, binary, binary_compressed) read through ReadMesh, from a file held
// in memory (fuzz_file.h).
#include <cstddef>
#include <cstdint>

#include "shape/core/error.h"
#include "shape/io/mesh_io.h"
#include "tests/fuzz/fuzz_file.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static pectus::fuzz::FuzzFile file(".pcd");
  const auto& path = file.Write(data, size);
  pectus::ReadOptions options;
  options.warn_units = false;
  try {
    pectus::ReadMesh(path, options);
  } catch (const pectus::Error&) {
  }
  return 0;
}
