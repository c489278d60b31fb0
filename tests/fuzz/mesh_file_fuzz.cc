// libFuzzer target: ReadMesh through the file path (open, memory map, dispatch by extension, validation,
// unit scaling). The first byte picks the extension; the rest is the file, held in memory (fuzz_file.h).
#include <cstddef>
#include <cstdint>
#include <memory>

#include "shape/core/error.h"
#include "shape/io/mesh_io.h"
#include "tests/fuzz/fuzz_file.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  static const char* const kExtensions[] = {".ply", ".obj", ".stl", ".xyz", ".csv"};
  static pectus::fuzz::FuzzFile* files[5] = {};
  const std::size_t which = data[0] % 5;
  if (files[which] == nullptr) files[which] = new pectus::fuzz::FuzzFile(kExtensions[which]);
  const auto& path = files[which]->Write(data + 1, size - 1);
  pectus::ReadOptions options;
  options.warn_units = false;
  options.input_units = data[0] / 5 % 2 ? pectus::LengthUnit::kMetre : pectus::LengthUnit::kMillimetre;
  try {
    pectus::FileSummary summary;
    pectus::ReadMesh(path, options, &summary);
  } catch (const pectus::Error&) {
  }
  return 0;
}
