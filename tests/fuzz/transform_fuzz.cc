// libFuzzer target: transforms as JSON ("T_target_source", "scale").
#include <cstddef>
#include <cstdint>
#include <string>

#include "shape/core/error.h"
#include "shape/io/transform_io.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    pectus::ParseTransformJson(std::string(reinterpret_cast<const char*>(data), size), "fuzz.json");
  } catch (const pectus::Error&) {
  }
  return 0;
}
