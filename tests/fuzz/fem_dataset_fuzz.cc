// libFuzzer target: the FE dataset .h5 reader, on HDF5 file images built from the fuzzer's bytes
// (h5_image.h): 2 load cases, 2 faces over 4 surface nodes, 2 patients (57 with a response basis), each
// dataset present, missing or malformed.
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
    // Patient 57's response basis: 2 output points (a bone vertex, a skin vertex), rank 1, 2 contact nodes,
    // 2 quadrature points.
    const std::string b = "patients/57/response_basis/";
    layout.push_back(Numbers(b + "scalars", {10}, {2, 12, 0, 150, 0, 1, 1, 0, 10, 0}));
    layout.push_back(Numbers(b + "modes", {6, 1}, {0.5, 0, 0.5, 0, 0.5, 0.5}, H5T_NATIVE_FLOAT));
    layout.push_back(Numbers(b + "mixing", {1, 2}, {0.1, 0.2}));
    layout.push_back(Numbers(b + "lift", {2}, {0.01, 0.02}));
    layout.push_back(Numbers(b + "contact_nodes", {2}, {3, 4}, H5T_NATIVE_INT32));
    layout.push_back(Numbers(b + "quadrature_z", {2}, {-10, -5}));
    layout.push_back(Numbers(b + "quadrature_weight", {2}, {1, 1}));
    layout.push_back(
        Numbers(b + "quadrature_contact", {2, 6}, {0, 1, 0, 1, 0, 1, 1, 0, 1, 0, 1, 0}, H5T_NATIVE_INT32));
    layout.push_back(Numbers(b + "quadrature_N", {2, 6}, std::vector<double>(12, 1.0 / 6)));
    layout.push_back(Numbers(b + "singular_values", {2}, {1.0, 0.1}));
    return layout;
  }();
  const std::vector<char> image = pectus::fuzz::BuildImage(kLayout, data, size);
  try {
    pectus::planner::ParseFemDataset(std::string_view(image.data(), image.size()), "fuzz.h5");
  } catch (const pectus::Error&) {
  }
  return 0;
}
