#include "shape/core/number_format.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>

#include "shape/core/error.h"

namespace pectus {

std::string FormatSignificant(double value, int digits) {
  digits = std::max(digits, 1);
  if (std::isnan(value)) return "nan";
  if (std::isinf(value)) return value > 0 ? "inf" : "-inf";
  if (value == 0.0) return "0";
  char text[64];
  const double magnitude = std::abs(value);
  if (magnitude < 1e-3) {
    std::snprintf(text, sizeof(text), "%.*e", digits - 1, value);
    return text;
  }
  // Decimals that leave `digits` significant ones; one fewer when rounding carries into the next power of
  // ten (9.996 to 3 digits is "10.0", not "10.00").
  const int exponent = static_cast<int>(std::floor(std::log10(magnitude)));
  int decimals = std::max(0, digits - 1 - exponent);
  const double scale = std::pow(10.0, decimals);
  if (decimals > 0 && std::round(magnitude * scale) / scale >= std::pow(10.0, exponent + 1)) --decimals;
  std::snprintf(text, sizeof(text), "%.*f", decimals, value);
  return text;
}

std::string FormatMm(double mm) { return FormatSignificant(mm) + " mm"; }

std::string ExactText(double value) {
  char text[64];
  std::snprintf(text, sizeof text, "%a", value);
  return text;
}

double ReadExactText(const std::string& path) {
  std::ifstream in(path);
  std::string text;
  in >> text;
  char* end = nullptr;
  const double value = std::strtod(text.c_str(), &end);
  if (text.empty() || *end != '\0') ThrowBadInput(path, "does not hold a number");
  return value;
}

}  // namespace pectus
