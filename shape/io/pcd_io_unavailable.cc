// PCD reading needs PCL, which the core-only (sanitizer and fuzz) builds leave out.
#include "shape/core/error.h"
#include "shape/io/format_parsers.h"

namespace pectus {

TriangleMesh ReadPcdFile(const std::string& path, FileSummary*) {
  ThrowUsage(path + ": this build of pectus was made without PCL and cannot read PCD files");
}

}  // namespace pectus
