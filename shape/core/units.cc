#include "shape/core/units.h"

#include <cstdio>

#include "shape/core/enum_names.h"
#include "shape/core/error.h"

namespace pectus {

namespace {
constexpr EnumNames<LengthUnit, 4> kUnitNames{{{LengthUnit::kMillimetre, "mm"},
                                               {LengthUnit::kCentimetre, "cm"},
                                               {LengthUnit::kMetre, "m"},
                                               {LengthUnit::kInch, "in"}}};
}  // namespace

LengthUnit ParseLengthUnit(const std::string& text) {
  return ParseEnum(kUnitNames, text, [&] {
    return "unknown length unit '" + text + "' (expected " + ListEnumNames(kUnitNames, "", ", ", " or ") +
           ")";
  });
}

std::string ToString(LengthUnit unit) { return EnumToString(kUnitNames, unit, "mm"); }

double MillimetresPer(LengthUnit unit) {
  switch (unit) {
    case LengthUnit::kMillimetre: return 1.0;
    case LengthUnit::kCentimetre: return 10.0;
    case LengthUnit::kMetre: return 1000.0;
    case LengthUnit::kInch: return 25.4;
  }
  return 1.0;
}

namespace {
constexpr double kSmallestMm = 5.0;    // a scanned object smaller than this is implausible
constexpr double kLargestMm = 5000.0;  // and so is one larger than this
}  // namespace

std::optional<LengthUnit> GuessLengthUnit(const Bounds3& bounds) {
  if (bounds.empty()) return std::nullopt;
  const double d = bounds.diagonal();
  if (d <= 0) return std::nullopt;
  // Prefer millimetres, then metres: the units scanners actually write.
  for (LengthUnit u : {LengthUnit::kMillimetre, LengthUnit::kMetre, LengthUnit::kCentimetre}) {
    const double mm = d * MillimetresPer(u);
    if (mm >= 10.0 && mm <= 3000.0) return u;
  }
  return std::nullopt;
}

std::string UnitsWarning(const std::string& file, const Bounds3& bounds, LengthUnit unit) {
  if (bounds.empty()) return {};
  const double mm = bounds.diagonal() * MillimetresPer(unit);
  if (mm >= kSmallestMm && mm <= kLargestMm) return {};
  char size[64];
  std::snprintf(size, sizeof size, "%.4g mm", mm);
  std::string msg =
      file + ": read as " + ToString(unit) + ", the object is " + size + " across, which looks wrong";
  if (auto guess = GuessLengthUnit(bounds); guess && *guess != unit) {
    msg +=
        "; its coordinates look like " + ToString(*guess) + " (pass --input-units " + ToString(*guess) + ")";
  }
  return msg;
}

}  // namespace pectus
