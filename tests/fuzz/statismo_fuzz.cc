// libFuzzer target: the statismo .h5 reader, on HDF5 file images built from the fuzzer's bytes
// (h5_image.h): a model of 4 points and 2 modes, each dataset present, missing or malformed.
#include <cstddef>
#include <cstdint>
#include <string_view>
#include <vector>

#include "shape/core/error.h"
#include "shape/model/statismo_io.h"
#include "tests/fuzz/h5_image.h"

namespace {

std::vector<double> Ramp(std::size_t n, double start, double step) {
  std::vector<double> v(n);
  for (std::size_t i = 0; i < n; ++i) v[i] = start + step * static_cast<double>(i);
  return v;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using pectus::fuzz::Numbers;
  using pectus::fuzz::Slot;
  using pectus::fuzz::Text;
  static const std::vector<Slot> kLayout = [] {
    std::vector<double> basis(12 * 2, 0.0);  // orthonormal columns: unit vectors e0 and e1
    basis[0 * 2 + 0] = 1.0;
    basis[1 * 2 + 1] = 1.0;
    return std::vector<Slot>{
        Numbers("version/majorVersion", {}, {0}, H5T_NATIVE_INT32),
        Numbers("version/minorVersion", {}, {9}, H5T_NATIVE_INT32),
        Numbers("model/mean", {12}, Ramp(12, 0.0, 1.0), H5T_NATIVE_FLOAT),
        Numbers("model/pcaVariance", {2}, {4.0, 1.0}, H5T_NATIVE_FLOAT),
        Numbers("model/pcaBasis", {12, 2}, basis, H5T_NATIVE_FLOAT),
        Numbers("model/noiseVariance", {}, {0.0}, H5T_NATIVE_FLOAT),
        Numbers("representer/points", {3, 4}, Ramp(12, 0.0, 1.0), H5T_NATIVE_FLOAT),
        Numbers("representer/cells", {3, 2}, {0, 1, 1, 2, 2, 3}, H5T_NATIVE_INT32),
        Numbers("modelinfo/scores", {2, 3}, {1, -1, 0, 0.5, 0.5, -1}, H5T_NATIVE_FLOAT),
        Text("modelinfo/modelBuilder-0/dataInfo/URI_0", "a.ply"),
        Text("modelinfo/modelBuilder-0/dataInfo/URI_1", "b.ply"),
        Text("modelinfo/modelBuilder-0/dataInfo/URI_2", "c.ply"),
        Numbers("pectus/totalVariance", {}, {5.0}, H5T_NATIVE_DOUBLE),
        Text("pectus/info", "{\"subjects\": 3}"),
    };
  }();
  const std::vector<char> image = pectus::fuzz::BuildImage(kLayout, data, size);
  try {
    nlohmann::json info;
    pectus::ParseStatismoModel(std::string_view(image.data(), image.size()), "fuzz.h5", &info);
  } catch (const pectus::Error&) {
  }
  return 0;
}
