// The shared datasets folder (`shared/` beside the repository, ../shared): where the tests and benchmarks
// find the real data, and the one message they give when it is not there.
#pragma once

#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <string>

namespace pectus::testing_support {

/// The CT table of 62 patients, relative to the shared folder.
inline constexpr const char* kPatientTable = "datasets/patients/nuss_ct_parameters.csv";
/// The published placements of the ten Stanford bunny sweeps, relative to the shared folder.
inline constexpr const char* kBunnyConf = "datasets/stanford_bunny/bun.conf";

/// The shared folder: the environment variable PECTUS_SHARED_DIR when it is set (a run can point
/// elsewhere without a rebuild), else the folder configured at build time (CMake's PECTUS_SHARED_DIR,
/// ../shared beside the repository by default).
inline std::filesystem::path SharedDirectory() {
  const char* from_environment = std::getenv("PECTUS_SHARED_DIR");
  if (from_environment != nullptr && *from_environment != '\0') return from_environment;
  return PECTUS_SHARED_DIR;
}

/// The path of `relative` (e.g. kPatientTable) in the shared folder.
inline std::string SharedPath(const std::string& relative) { return (SharedDirectory() / relative).string(); }

/// Empty if `relative` is a file of the shared folder; else what is missing, where it was looked for and
/// where it comes from.
inline std::string MissingSharedFile(const std::string& relative) {
  const std::filesystem::path dir = SharedDirectory();
  std::error_code ignored;
  if (std::filesystem::is_regular_file(dir / relative, ignored)) return "";
  const bool no_folder = !std::filesystem::is_directory(dir, ignored);
  return SharedPath(relative) + " is missing: the shared datasets folder " + dir.string() +
         (no_folder ? " does not exist" : " does not hold it") +
         ". It is the shared/ folder that sits beside the repository (../shared, see README, 'Two "
         "commands'), with datasets/stanford_bunny (the Stanford 3D Scanning Repository's bunny sweeps) and "
         "datasets/patients (the CT table of 62 patients), each with a SOURCE.md saying where it comes from. "
         "Put it there, or point to it with the environment variable PECTUS_SHARED_DIR=DIR or with cmake "
         "-DPECTUS_SHARED_DIR=DIR.";
}

/// The bunny folder of the shared datasets, with a trailing slash.
inline std::string BunnyDirectory() { return SharedPath("datasets/stanford_bunny/"); }

/// The CT table of 62 patients (kPatientTable) in the shared folder.
inline std::string PatientTablePath() { return SharedPath(kPatientTable); }

/// For a benchmark's main(): true if `relative` is in the shared folder; else prints
/// "PROGRAM: error: MESSAGE" (MissingSharedFile) to stderr and returns false; main then returns 3, the
/// exit code of bad input (docs/errors.md).
inline bool HaveSharedFile(const std::string& program, const std::string& relative) {
  const std::string missing = MissingSharedFile(relative);
  if (missing.empty()) return true;
  std::cerr << program << ": error: " << missing << "\n";
  return false;
}

}  // namespace pectus::testing_support
