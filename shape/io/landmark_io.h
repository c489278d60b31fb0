// pectus: landmark files. 3D Slicer markups (.mrk.json), legacy Slicer .fcsv, and CSV label,x,y,z.
#pragma once

#include <filesystem>
#include <string>
#include <string_view>

#include "shape/core/landmarks.h"
#include "shape/core/units.h"

namespace pectus {

/// Options for reading landmarks.
struct LandmarkReadOptions {
  LengthUnit input_units = LengthUnit::kMillimetre;  ///< positions are scaled to mm
};

/// Reads a landmark file, format from the name: *.mrk.json, *.json, *.fcsv, *.csv.
/// Positions come back in LPS (the frame of Slicer's model files): Slicer's RAS coordinates (a .fcsv
/// says RAS unless its header says LPS; a .mrk.json says which in "coordinateSystem") are converted by
/// negating x and y. CSV is taken as it stands. Throws Error(kBadInput) naming the file and line for a
/// missing, empty or duplicate label, a non-finite or missing coordinate, or a malformed file.
LandmarkSet ReadLandmarks(const std::filesystem::path& path, const LandmarkReadOptions& options = {});

/// The same from memory; `name` decides the format as the path does above.
LandmarkSet ParseLandmarks(std::string_view bytes, const std::string& name,
                           const LandmarkReadOptions& options = {});

/// Writes landmarks atomically: .mrk.json (Slicer 5 markups schema, coordinateSystem LPS), .fcsv
/// (version 4.11 header, LPS) or .csv (label,x,y,z).
void WriteLandmarks(const std::filesystem::path& path, const LandmarkSet& landmarks);

}  // namespace pectus
