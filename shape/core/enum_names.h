// pectus: the names of an enum's values in one table, for parsing option text and printing values
// (ParseRobustLoss/ToString, ParseLengthUnit/ToString, ...), instead of an if/else chain and a switch
// that must be kept alike by hand.
#pragma once

#include <array>
#include <cstddef>
#include <optional>
#include <string>
#include <string_view>

#include "shape/core/error.h"

namespace pectus {

/// One value of an enum and its name, as written on command lines and in reports.
template <class Enum>
struct EnumName {
  Enum value;
  std::string_view name;
};

/// An enum's names, in the order messages list them, e.g.
///   constexpr EnumNames<LengthUnit, 2> kUnitNames{{{LengthUnit::kMillimetre, "mm"}, {LengthUnit::kMetre,
///   "m"}}};
template <class Enum, std::size_t N>
using EnumNames = std::array<EnumName<Enum>, N>;

/// The value named `text`, or nullopt if no value has that name.
template <class Enum, std::size_t N>
std::optional<Enum> FindEnum(const EnumNames<Enum, N>& names, std::string_view text) {
  for (const EnumName<Enum>& n : names) {
    if (n.name == text) return n.value;
  }
  return std::nullopt;
}

/// The value named `text`. Otherwise throws Error(kUsage) with the text `message()` returns (a callable,
/// so that the message, which usually lists the names with ListEnumNames, is made only on failure).
template <class Enum, std::size_t N, class Message>
Enum ParseEnum(const EnumNames<Enum, N>& names, std::string_view text, const Message& message) {
  if (const std::optional<Enum> value = FindEnum(names, text)) return *value;
  ThrowUsage(message());
}

/// The name of `value`; `unnamed` if the table has none (a value cast from an out-of-range integer).
template <class Enum, std::size_t N>
std::string EnumToString(const EnumNames<Enum, N>& names, Enum value, std::string_view unnamed = "?") {
  for (const EnumName<Enum>& n : names) {
    if (n.value == value) return std::string(n.name);
  }
  return std::string(unnamed);
}

/// The names for a message, each between `quote`s, joined by `separator` except the last two, which
/// are joined by `last_separator`: ListEnumNames(names, "'", ", ", " or ") gives "'a', 'b' or 'c'".
template <class Enum, std::size_t N>
std::string ListEnumNames(const EnumNames<Enum, N>& names, std::string_view quote, std::string_view separator,
                          std::string_view last_separator) {
  std::string list;
  for (std::size_t i = 0; i < N; ++i) {
    if (i > 0) list += i + 1 == N ? last_separator : separator;
    list += quote;
    list += names[i].name;
    list += quote;
  }
  return list;
}

}  // namespace pectus
