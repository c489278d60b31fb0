// libFuzzer target: the FE dataset .h5 reader, on HDF5 file images built from the fuzzer's bytes
// (h5_image.h): 2 load cases, 2 faces over 4 surface nodes, 2 patients, each dataset present, missing
// or malformed.
#include <cstddef>
#include <cstdint>
#include <string_view>
#include <vector>

#include "planner_plugin/io/fem_dataset_h5.h"
#include "shape/core/error.h"
#include "tests/fuzz/h5_image.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using pectus::fuzz::Numbers;
  using pectus::fuzz::Slot;
  using pectus::fuzz::Text;
  static const std::vector<Slot> kLayout = [] {
    std::vector<Slot> layout{
        Numbers("load_cases/position", {2}, {0.25, 0.5}),
        Numbers("load_cases/force_n", {2}, {50.0, 100.0}),
        Numbers("topology/faces", {2, 3}, {0, 1, 2, 1, 3, 2}, H5T_NATIVE_INT32),
        Numbers("topology/face_region", {2}, {0, 2}, H5T_NATIVE_INT32),
        Numbers("topology/face_part", {2}, {0, -3}, H5T_NATIVE_INT32),
    };
    for (const char* id : {"patients/3", "patients/57"}) {
      const std::string p = id;
      layout.push_back(Numbers(p + "/nodes", {4, 3}, {0, 0, 0, 10, 0, 0, 0, 10, 0, 10, 10, 1}));
      layout.push_back(
          Numbers(p + "/displacements", {2, 4, 3}, std::vector<double>(24, 0.5), H5T_NATIVE_FLOAT));
      layout.push_back(Numbers(p + "/sternum_lift", {2}, {1.0, 2.0}));
    }
    return layout;
  }();
  const std::vector<char> image = pectus::fuzz::BuildImage(kLayout, data, size);
  try {
    pectus::planner::ParseFemDataset(std::string_view(image.data(), image.size()), "fuzz.h5");
  } catch (const pectus::Error&) {
  }
  return 0;
}
