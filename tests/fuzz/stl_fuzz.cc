// libFuzzer target: the STL parser must never crash, hang or read out of bounds; bad input is an Error.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "shape/core/error.h"
#include "shape/io/format_parsers.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    pectus::FileSummary summary;
    const pectus::TriangleMesh mesh =
        pectus::ParseStl(std::string_view(reinterpret_cast<const char*>(data), size), "fuzz.stl", &summary);
    mesh.Validate("fuzz.stl");
  } catch (const pectus::Error&) {
  }
  return 0;
}
