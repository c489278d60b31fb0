// pectus: figures for people to read: a number with the significant digits its size calls for, so that
// a summary says "RMS 0.0123 mm, p95 2.40 mm" rather than "0.012298 mm" or "2.39732 mm".
#pragma once

#include <string>

namespace pectus {

/// `value` with `digits` significant digits (>= 1): fixed notation from 0.001 up ("2.40", "0.0123",
/// "1235": an integer part is never cut), scientific below ("4.20e-05"); "0" for zero, "nan", "inf" and
/// "-inf" for the non-finite.
std::string FormatSignificant(double value, int digits = 3);

/// A length for a summary line: FormatSignificant(mm) followed by " mm".
std::string FormatMm(double mm);

/// `value` as text that reads back to the same bits (hexadecimal floating point, "%a"): for numbers one
/// process writes and another reads (the task farm's work files).
std::string ExactText(double value);

/// The number ExactText wrote (any text strtod reads) in the file at `path`; throws Error(kBadInput)
/// naming the file if it holds no number.
double ReadExactText(const std::string& path);

}  // namespace pectus
