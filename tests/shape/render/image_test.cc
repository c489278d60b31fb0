// Images: PNG round trip is lossless, stacking places pixels, plots put data where the axes say.
#include "shape/render/image.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "shape/core/error.h"
#include "shape/render/plot.h"

namespace pectus::render {
namespace {

TEST(Image, PngRoundTripIsExact) {
  Image im(7, 5, kWhite);
  im.Set(3, 2, Rgb{10, 200, 30});
  im.Set(6, 4, Rgb{1, 2, 3});
  const auto path = std::filesystem::temp_directory_path() / "pectus_render_roundtrip.png";
  WritePng(im, path);
  const Image back = ReadImage(path);
  std::filesystem::remove(path);
  ASSERT_EQ(back.width, 7);
  ASSERT_EQ(back.height, 5);
  EXPECT_EQ(back.rgb, im.rgb);
}

TEST(Image, StacksPlaceImagesSideBySideAndAbove) {
  Image a(2, 3, Rgb{255, 0, 0}), b(4, 1, Rgb{0, 0, 255});
  const Image h = HStack({a, b}, 1);
  EXPECT_EQ(h.width, 7);
  EXPECT_EQ(h.height, 3);
  EXPECT_EQ(h.at(1, 2).r, 255);
  EXPECT_EQ(h.at(3, 0).b, 255);
  EXPECT_EQ(h.at(3, 2).r, 255);  // padding is white
  EXPECT_EQ(h.at(3, 2).g, 255);
  const Image v = VStack({a, b});
  EXPECT_EQ(v.width, 4);
  EXPECT_EQ(v.height, 4);
  EXPECT_EQ(v.at(0, 3).b, 255);
}

TEST(Image, ReadingANonImageNamesTheFile) {
  const auto path = std::filesystem::temp_directory_path() / "pectus_not_an_image.png";
  { std::ofstream(path) << "hello"; }
  try {
    ReadImage(path);
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("pectus_not_an_image.png"), std::string::npos);
  }
  std::filesystem::remove(path);
}

TEST(Image, ReadingATruncatedPngNamesTheFile) {
  Image im(64, 48, kWhite);
  for (int y = 0; y < 48; ++y)
    for (int x = 0; x < 64; ++x)
      im.Set(x, y, Rgb{static_cast<std::uint8_t>(x * 4), static_cast<std::uint8_t>(y * 5), 7});
  const std::string png = EncodePng(im);
  ASSERT_EQ(png.substr(0, 4), "\x89PNG");
  const auto path = std::filesystem::temp_directory_path() / "pectus_truncated.png";
  { std::ofstream(path, std::ios::binary) << png.substr(0, png.size() / 2); }  // header intact, data cut
  try {
    ReadImage(path);
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("pectus_truncated.png"), std::string::npos) << e.what();
  }
  std::filesystem::remove(path);
}

TEST(Plot, HorizontalLineLandsOnItsValue) {
  PlotOptions o;
  o.width = 400;
  o.height = 300;
  o.y_min = 0;
  o.y_max = 10;
  Series s;
  s.x = {0, 1};
  s.y = {5, 5};
  s.colour = Rgb{255, 0, 0};
  s.markers = false;
  const Image im = PlotLines({s}, o);
  // Axes: top 40, bottom = height - 60 = 240; y = 5 of [0, 10] is row 140.
  bool red_near = false;
  for (int y = 138; y <= 142; ++y) red_near |= im.at(200, y).r > 200 && im.at(200, y).g < 80;
  EXPECT_TRUE(red_near);
  EXPECT_GT(im.at(200, 100).g, 200);  // above the line: background or grid, not red
}

}  // namespace
}  // namespace pectus::render
