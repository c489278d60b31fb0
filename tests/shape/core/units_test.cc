#include "shape/core/units.h"

#include <gtest/gtest.h>

#include "shape/core/error.h"

namespace pectus {
namespace {

Bounds3 Box(double size) {
  Bounds3 b;
  b.min.setZero();
  b.max = Eigen::Vector3d::Constant(size / std::sqrt(3.0));
  return b;
}

TEST(Units, ParseAndScale) {
  EXPECT_EQ(ParseLengthUnit("m"), LengthUnit::kMetre);
  EXPECT_DOUBLE_EQ(MillimetresPer(LengthUnit::kMetre), 1000.0);
  EXPECT_DOUBLE_EQ(MillimetresPer(LengthUnit::kInch), 25.4);
  EXPECT_THROW(ParseLengthUnit("furlong"), Error);
}

TEST(Units, BunnyInMetresLooksLikeMetres) {
  // The bunny is 0.156 x 0.153 x 0.118 m: read as mm it would be a 0.25 mm speck.
  const Bounds3 bunny = Box(0.25);
  EXPECT_EQ(GuessLengthUnit(bunny), LengthUnit::kMetre);
  const std::string w = UnitsWarning("bun000.ply", bunny, LengthUnit::kMillimetre);
  EXPECT_NE(w.find("bun000.ply"), std::string::npos);
  EXPECT_NE(w.find("--input-units m"), std::string::npos);
  EXPECT_TRUE(UnitsWarning("bun000.ply", bunny, LengthUnit::kMetre).empty());
}

TEST(Units, ChestInMillimetresIsQuiet) {
  const Bounds3 chest = Box(400.0);
  EXPECT_EQ(GuessLengthUnit(chest), LengthUnit::kMillimetre);
  EXPECT_TRUE(UnitsWarning("chest.ply", chest, LengthUnit::kMillimetre).empty());
  EXPECT_FALSE(UnitsWarning("chest.ply", chest, LengthUnit::kMetre).empty());  // a 400 m chest
}

}  // namespace
}  // namespace pectus
