// Colour maps: end points, centre of the diverging map, clamping and NaN.
#include "shape/render/colormap.h"

#include <gtest/gtest.h>

#include <cmath>

namespace pectus::render {
namespace {

TEST(Colormap, ViridisEndsAreDarkPurpleAndYellow) {
  const Rgb lo = MapColor(0, 0, 1, Colormap::kViridis), hi = MapColor(1, 0, 1, Colormap::kViridis);
  // matplotlib's viridis: #440154 at 0 and #fde725 at 1 (OpenCV's table matches within 2 levels).
  EXPECT_NEAR(lo.r, 0x44, 2);
  EXPECT_NEAR(lo.g, 0x01, 2);
  EXPECT_NEAR(lo.b, 0x54, 2);
  EXPECT_NEAR(hi.r, 0xfd, 2);
  EXPECT_NEAR(hi.g, 0xe7, 2);
  EXPECT_NEAR(hi.b, 0x25, 2);
}

TEST(Colormap, DivergingIsWhiteAtZeroAndClamps) {
  const Rgb mid = MapColor(0, -2, 2, Colormap::kDiverging);
  EXPECT_GE(mid.r, 240);
  EXPECT_GE(mid.g, 240);
  EXPECT_GE(mid.b, 240);
  const Rgb below = MapColor(-100, -2, 2, Colormap::kDiverging),
            lo = MapColor(-2, -2, 2, Colormap::kDiverging);
  EXPECT_EQ(below.b, lo.b);
  EXPECT_GT(lo.b, lo.r);  // blue for negative
  const Rgb hi = MapColor(2, -2, 2, Colormap::kDiverging);
  EXPECT_GT(hi.r, hi.b);  // red for positive
  const Rgb nan = MapColor(std::nan(""), -2, 2, Colormap::kDiverging);
  EXPECT_EQ(nan.r, kGrey.r);
}

TEST(Colormap, MapColorsGivesOneRowPerValue) {
  Eigen::VectorXd v(3);
  v << 0, 0.5, 1;
  const Colors3 c = MapColors(v, 0, 1, Colormap::kTurbo);
  ASSERT_EQ(c.rows(), 3);
  const Rgb mid = MapColor(0.5, 0, 1, Colormap::kTurbo);
  EXPECT_EQ(c(1, 0), mid.r);
  EXPECT_EQ(c(1, 1), mid.g);
}

TEST(Colormap, ColorBarShowsTheMapTopToBottom) {
  const Image bar = ColorBar(0, 10, Colormap::kViridis, "mm", 300);
  ASSERT_EQ(bar.height, 300);
  const Rgb top = bar.at(20, 34), bottom = bar.at(20, 300 - 25);  // inside the border
  const Rgb hi = MapColor(10, 0, 10, Colormap::kViridis), lo = MapColor(0, 0, 10, Colormap::kViridis);
  EXPECT_NEAR(top.g, hi.g, 8);
  EXPECT_NEAR(bottom.g, lo.g, 8);
}

void ExpectTicks(const std::vector<double>& actual, const std::vector<double>& expected) {
  ASSERT_EQ(actual.size(), expected.size());
  for (std::size_t i = 0; i < actual.size(); ++i) EXPECT_NEAR(actual[i], expected[i], 1e-12) << i;
}

TEST(Colormap, NiceTicksAreRoundAndInsideTheRange) {
  ExpectTicks(NiceTicks(-16, 16, 6), {-15, -10, -5, 0, 5, 10, 15});
  ExpectTicks(NiceTicks(0, 1, 6), {0, 0.2, 0.4, 0.6, 0.8, 1});
  ExpectTicks(NiceTicks(0, 485, 6), {0, 100, 200, 300, 400});
  ExpectTicks(NiceTicks(3.2, 3.9, 4), {3.2, 3.4, 3.6, 3.8});
  EXPECT_TRUE(NiceTicks(1, 1, 6).empty());
}

}  // namespace
}  // namespace pectus::render
