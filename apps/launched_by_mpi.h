// pectus command line: whether an MPI launcher started this process. No MPI type or call: `pectus`, which
// hands every command run under mpirun to `pectus-full`, asks it too without linking MPI.
#pragma once

#include <cstdlib>

namespace pectus::cli {

/// True if this process was started by an MPI launcher (mpirun, or srun with PMIx/PMI2): Open MPI's,
/// PMIx's or PMI's rank variable is set. A plain `pectus` run never starts MPI.
inline bool LaunchedByMpi() {
  for (const char* name : {"OMPI_COMM_WORLD_SIZE", "PMIX_RANK", "PMI_RANK"}) {
    if (std::getenv(name) != nullptr) return true;
  }
  return false;
}

}  // namespace pectus::cli
