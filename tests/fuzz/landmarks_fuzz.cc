// libFuzzer target: the landmark parsers (.mrk.json, .fcsv, .csv; the first byte picks one).
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "shape/core/error.h"
#include "shape/io/landmark_io.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  static const char* const kNames[] = {"fuzz.mrk.json", "fuzz.fcsv", "fuzz.csv"};
  const char* name = kNames[data[0] % 3];
  try {
    const pectus::LandmarkSet set =
        pectus::ParseLandmarks(std::string_view(reinterpret_cast<const char*>(data) + 1, size - 1), name);
    set.Validate(name);
  } catch (const pectus::Error&) {
  }
  return 0;
}
