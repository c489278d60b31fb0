// libFuzzer target: the Stanford .conf parser.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "shape/core/error.h"
#include "shape/io/stanford_conf.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    pectus::ParseStanfordConf(std::string_view(reinterpret_cast<const char*>(data), size), "fuzz.conf");
  } catch (const pectus::Error&) {
  }
  return 0;
}
