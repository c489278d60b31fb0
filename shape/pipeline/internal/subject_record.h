// pectus pipeline: one subject's outcome as a file, bit for bit (its fields as CBOR, numbers as IEEE
// doubles; its arrays as raw little-endian bytes after the CBOR, each referred to by its offset), so that a
// subject computed by another process, or by an earlier run that was killed, reads back exactly as if it had
// been computed here (docs/cluster.md).
#pragma once

#include <filesystem>

#include "shape/pipeline/cohort_pipeline.h"

namespace pectus::internal {

/// Writes `subject` (every field, those of the model stage too: its alignment, fills, scores and distances
/// to the mean) to `path` atomically.
void WriteSubjectRecord(const std::filesystem::path& path, const SubjectOutcome& subject);

/// Reads a record written by WriteSubjectRecord. Throws Error(kBadInput) naming the file if it is not one.
SubjectOutcome ReadSubjectRecord(const std::filesystem::path& path);

}  // namespace pectus::internal
