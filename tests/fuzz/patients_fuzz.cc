// libFuzzer target: the patient table (CSV of CT measurements).
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "shape/core/error.h"
#include "shape/io/patient_table_io.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    const auto rows =
        pectus::ParsePatientTable(std::string_view(reinterpret_cast<const char*>(data), size), "fuzz.csv");
    pectus::FindPatient(rows, rows.front().patient, "fuzz.csv");
  } catch (const pectus::Error&) {
  }
  return 0;
}
