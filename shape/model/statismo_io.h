// pectus: shape models as statismo HDF5 files (format version 0.9), which statismo and Scalismo read.
// The only file that includes HDF5.
#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>

#include "shape/model/shape_model.h"

namespace pectus {

/// Writes `model` atomically as a statismo 0.9 file:
///   /version/majorVersion = 0, /version/minorVersion = 9        (int32 scalars)
///   /model/mean           float32 [3m]                          (x1, y1, z1, ...)
///   /model/pcaBasis       float32 [3m, k], orthonormal columns   (row-major)
///   /model/pcaVariance    float32 [k]
///   /model/noiseVariance  float32 scalar
///   /representer          attributes name = "itkStandardMeshRepresenter", version = "1.0",
///                         datasetType = "POLYGON_MESH" ("POINT_SET" without faces);
///                         points float32 [3, m] (the mean shape), cells int32 [3, #faces], pointData
///   /modelinfo            build-time, scores float32 [k, N], modelBuilder-0/{builderName, buildTime,
///                         dataInfo/URI_n, parameters/...}
///   /pectus               totalVariance float64, info (JSON text: `info`)
/// Throws Error(kUsage) for a model without modes, Error(kFailure) naming the file if HDF5 fails.
void WriteStatismoModel(const std::filesystem::path& path, const ShapeModel& model,
                        const nlohmann::json& info = nlohmann::json::object());

/// Reads a statismo file (version 0.8, whose basis is scaled by the standard deviations, or 0.9) with a
/// mesh or point-set representer. Names come from /modelinfo/modelBuilder-0/dataInfo, scores from
/// /modelinfo/scores, the total variance from /pectus (else the sum of the variances).
/// @param[out] info  if not null, /pectus/info parsed (an empty object if absent)
/// Throws Error(kBadInput) naming the file and the dataset for anything missing or inconsistent.
ShapeModel ReadStatismoModel(const std::filesystem::path& path, nlohmann::json* info = nullptr);

/// ReadStatismoModel from a file held in memory (an HDF5 file image); `name` is the file named in errors.
ShapeModel ParseStatismoModel(std::string_view bytes, const std::string& name,
                              nlohmann::json* info = nullptr);

}  // namespace pectus
