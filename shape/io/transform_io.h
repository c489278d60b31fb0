// pectus: transforms as JSON: {"T_target_source": [[r00,r01,r02,tx],[...],[...],[0,0,0,1]], "scale": s}.
#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "shape/core/geometry.h"

namespace pectus {

/// Reads "T_target_source" (a 4 by 4 row-major array of arrays, or 16 numbers row-major). With a
/// scale, the 3 by 3 block is s R. Throws Error(kBadInput) naming the file for anything else.
Similarity3 ReadTransformJson(const std::filesystem::path& path);
Similarity3 ParseTransformJson(const std::string& text, const std::string& name);

/// The JSON object for a transform ("T_target_source", "scale", "rotation_deg", "translation_mm").
nlohmann::json TransformToJson(const Similarity3& T_target_source);
/// Writes TransformToJson(T) merged with `extra` atomically.
void WriteTransformJson(const std::filesystem::path& path, const Similarity3& T_target_source,
                        const nlohmann::json& extra = nlohmann::json::object());

}  // namespace pectus
