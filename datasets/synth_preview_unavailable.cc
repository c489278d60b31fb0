// pectus datasets: the preview functions when pectus::render is not part of the build.
#include "datasets/synth_preview.h"
#include "shape/core/error.h"

namespace pectus::datasets {

void WriteSubjectPreview(const ScannedSubject&, const std::filesystem::path&, const StagePath&) {
  ThrowUsage("pictures need pectus::render, which is not part of this build (PECTUS_COMPONENTS)");
}

}  // namespace pectus::datasets
