#include "shape/core/enum_names.h"

#include <gtest/gtest.h>

#include "shape/core/error.h"
#include "shape/core/units.h"

namespace pectus {
namespace {

enum class Fill { kProfiles, kInpaint, kInpaintInside };
constexpr EnumNames<Fill, 3> kFillNames{
    {{Fill::kProfiles, "profiles"}, {Fill::kInpaint, "inpaint"}, {Fill::kInpaintInside, "inpaint-inside"}}};

// The message of the Error(kUsage) that `parse` throws; empty if it throws none (or another kind).
template <class Parse>
std::string UsageMessage(const Parse& parse) {
  try {
    parse();
  } catch (const Error& e) {
    return e.kind() == ErrorKind::kUsage ? e.message() : std::string();
  }
  return {};
}

TEST(EnumNames, EveryNameParsesToItsValueAndBack) {
  for (const EnumName<Fill>& n : kFillNames) {
    const auto message = [] { return std::string("never"); };
    EXPECT_EQ(ParseEnum(kFillNames, n.name, message), n.value);
    EXPECT_EQ(EnumToString(kFillNames, n.value), n.name);
  }
  EXPECT_FALSE(FindEnum(kFillNames, "Inpaint").has_value());  // names are case-sensitive
  EXPECT_EQ(EnumToString(kFillNames, static_cast<Fill>(7)), "?");
  EXPECT_EQ(EnumToString(kFillNames, static_cast<Fill>(7), "profiles"), "profiles");
}

TEST(EnumNames, ListsTheNamesInTheStylesOfTheMessages) {
  EXPECT_EQ(ListEnumNames(kFillNames, "'", ", ", " or "), "'profiles', 'inpaint' or 'inpaint-inside'");
  EXPECT_EQ(ListEnumNames(kFillNames, "", ", ", ", "), "profiles, inpaint, inpaint-inside");
  const EnumNames<Fill, 1> one{{{Fill::kInpaint, "inpaint"}}};
  EXPECT_EQ(ListEnumNames(one, "'", ", ", " or "), "'inpaint'");
}

TEST(EnumNames, AnUnknownNameIsAUsageErrorWithTheGivenMessage) {
  const std::string text = "fill";
  EXPECT_EQ(UsageMessage([&] {
              ParseEnum(kFillNames, text, [&] {
                return "hole fill '" + text + "' is not " + ListEnumNames(kFillNames, "'", ", ", " or ");
              });
            }),
            "hole fill 'fill' is not 'profiles', 'inpaint' or 'inpaint-inside'");
}

TEST(EnumNames, LengthUnitsKeepTheirMessageAndNames) {
  EXPECT_EQ(UsageMessage([] { ParseLengthUnit("furlong"); }),
            "unknown length unit 'furlong' (expected mm, cm, m or in)");
  for (LengthUnit u :
       {LengthUnit::kMillimetre, LengthUnit::kCentimetre, LengthUnit::kMetre, LengthUnit::kInch})
    EXPECT_EQ(ParseLengthUnit(ToString(u)), u);
  EXPECT_EQ(ToString(LengthUnit::kInch), "in");
}

}  // namespace
}  // namespace pectus
