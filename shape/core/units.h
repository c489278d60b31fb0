// pectus: length units of input files. Everything inside pectus is in millimetres.
#pragma once

#include <optional>
#include <string>

#include "shape/core/geometry.h"

namespace pectus {

/// A length unit a file's coordinates may be in.
enum class LengthUnit { kMillimetre, kCentimetre, kMetre, kInch };

/// Parses "mm", "cm", "m", "in"; throws Error(kUsage) otherwise.
LengthUnit ParseLengthUnit(const std::string& text);
std::string ToString(LengthUnit unit);
/// Millimetres per one of `unit`.
double MillimetresPer(LengthUnit unit);

/// The unit that makes an object of these bounds look like a plausible scanned object (10 mm to 3 m
/// across), given the coordinates as stored in the file; nullopt if the file is empty or no unit fits.
std::optional<LengthUnit> GuessLengthUnit(const Bounds3& bounds_in_file_units);

/// If `unit` makes the bounds implausible (an object under 5 mm or over 5 m across), a warning naming
/// the file and the unit that looks right; otherwise empty.
std::string UnitsWarning(const std::string& file, const Bounds3& bounds_in_file_units, LengthUnit unit);

}  // namespace pectus
