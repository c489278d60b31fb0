// `pectus render` as a user meets it: a known mesh drawn where the front view must put it, in the colours
// of its scalar on the data's or a fixed scale with a colour bar; bad input exits 3 naming the file.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "shape/render/colormap.h"
#include "shape/render/image.h"
#include "tests/support/command_test.h"

namespace pectus {
namespace {

using RenderCommand = testing_support::CommandTest;
using render::Rgb;

// The right triangle (0,0,0), (100,0,0), (0,100,0) mm in the plane z = 0, facing the front view's camera.
const char* kTriangle =
    "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
    "element face 1\nproperty list uchar int vertex_indices\nend_header\n"
    "0 0 0\n100 0 0\n0 100 0\n3 0 1 2\n";

// The square [0, 100]^2 mm with a per-vertex scalar height_mm = x - 50: -50 on its left edge, 50 on its
// right.
const char* kSquare =
    "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
    "property float height_mm\nelement face 2\nproperty list uchar int vertex_indices\nend_header\n"
    "0 0 0 -50\n100 0 0 50\n100 100 0 50\n0 100 0 -50\n3 0 1 2\n3 0 2 3\n";

// In a 200 px picture the front view (along -z, y up) frames the 100 mm object with a 5 % margin: 180 px
// for 100 mm, x mm at column 10 + 1.8 x, y mm at row 190 - 1.8 y.
int Column(double x_mm) { return static_cast<int>(10.0 + 1.8 * x_mm); }
int Row(double y_mm) { return static_cast<int>(190.0 - 1.8 * y_mm); }

bool IsBackground(Rgb c) { return c.r == 255 && c.g == 255 && c.b == 255; }
// The largest difference of one channel.
int Difference(Rgb a, Rgb b) {
  return std::max({std::abs(a.r - b.r), std::abs(a.g - b.g), std::abs(a.b - b.b)});
}
// Whether some pixel at column x0 or right of it is within `tolerance` of `colour`.
bool HasColourRightOf(const render::Image& image, int x0, Rgb colour, int tolerance) {
  for (int y = 0; y < image.height; ++y)
    for (int x = x0; x < image.width; ++x)
      if (Difference(image.at(x, y), colour) <= tolerance) return true;
  return false;
}

TEST_F(RenderCommand, DrawsTheTriangleWhereTheFrontViewPutsIt) {
  Write("triangle.ply", kTriangle);
  const CliRun run = Pectus("render " + P("triangle.ply") + " -o " + P("triangle.png") +
                            " --size 200 --quiet --report " + P("r.json"));
  ASSERT_EQ(run.code, 0) << run.output;
  const render::Image image = render::ReadImage(P("triangle.png"));
  ASSERT_EQ(image.width, 200);
  ASSERT_EQ(image.height, 200);

  // Inside the triangle, near its right angle (bottom left: y is up), the base colour, unshaded: the
  // triangle faces the camera's headlight.
  const Rgb inside = image.at(Column(20.0), Row(20.0));
  EXPECT_LE(Difference(inside, Rgb{200, 190, 180}), 1)
      << int(inside.r) << "," << int(inside.g) << "," << int(inside.b);
  EXPECT_FALSE(IsBackground(image.at(Column(90.0), Row(5.0))));  // the tip on the x axis
  EXPECT_FALSE(IsBackground(image.at(Column(5.0), Row(90.0))));  // the tip on the y axis
  // Beyond the hypotenuse (top right) and in the margin: background.
  EXPECT_TRUE(IsBackground(image.at(Column(80.0), Row(80.0))));
  EXPECT_TRUE(IsBackground(image.at(2, 2)));
  EXPECT_TRUE(IsBackground(image.at(197, 197)));

  // Not blank, and no more than the triangle: half of its 180 x 180 px square, give or take the
  // 180 pixels the hypotenuse passes through.
  int drawn = 0;
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x) drawn += IsBackground(image.at(x, y)) ? 0 : 1;
  EXPECT_NEAR(drawn, 180 * 180 / 2, 180);

  std::ifstream in(P("r.json"));
  const nlohmann::json report = nlohmann::json::parse(in);
  EXPECT_EQ(report["points"], 3);
  EXPECT_EQ(report["faces"], 1);
}

TEST_F(RenderCommand, ColoursTheScalarOnTheDataRangeOrAFixedOneWithAColourBar) {
  Write("square.ply", kSquare);
  const auto map = render::Colormap::kDiverging;
  // The data's range, [-50, 50]: the left edge takes the scale's low end, the right edge its high end
  // (colours are interpolated between vertices: 2.5 mm in from an edge is 2.5 % of the way across).
  CliRun run =
      Pectus("render " + P("square.ply") + " -o " + P("data.png") +
             " --size 200 --scalar height_mm --colormap diverging --quiet --report " + P("data.json"));
  ASSERT_EQ(run.code, 0) << run.output;
  render::Image image = render::ReadImage(P("data.png"));
  EXPECT_GT(image.width, 200) << "the colour bar stands beside the picture";
  EXPECT_EQ(image.height, 200);
  const Rgb lo = render::MapColor(-50.0, -50.0, 50.0, map), hi = render::MapColor(50.0, -50.0, 50.0, map);
  EXPECT_LE(Difference(image.at(Column(2.5), Row(50.0)), lo), 6);
  EXPECT_LE(Difference(image.at(Column(97.5), Row(50.0)), hi), 6);
  EXPECT_TRUE(HasColourRightOf(image, 200, lo, 6)) << "the bar shows the low end";
  EXPECT_TRUE(HasColourRightOf(image, 200, hi, 6)) << "the bar shows the high end";
  {
    std::ifstream in(P("data.json"));
    const nlohmann::json report = nlohmann::json::parse(in);
    EXPECT_EQ(report["range"], nlohmann::json::array({-50.0, 50.0}));
  }

  // A fixed range, [-100, 100]: the edges take the colours of -50 and 50 on it, a quarter from each end.
  run = Pectus("render " + P("square.ply") + " -o " + P("fixed.png") +
               " --size 200 --scalar height_mm --range -100,100 --colormap diverging --quiet --report " +
               P("fixed.json"));
  ASSERT_EQ(run.code, 0) << run.output;
  image = render::ReadImage(P("fixed.png"));
  const Rgb quarter = render::MapColor(-50.0, -100.0, 100.0, map);
  const Rgb three_quarters = render::MapColor(50.0, -100.0, 100.0, map);
  EXPECT_GT(Difference(quarter, lo), 20) << "the two scales differ where the test looks";
  EXPECT_LE(Difference(image.at(Column(2.5), Row(50.0)), quarter), 6);
  EXPECT_LE(Difference(image.at(Column(97.5), Row(50.0)), three_quarters), 6);
  std::ifstream in(P("fixed.json"));
  const nlohmann::json report = nlohmann::json::parse(in);
  EXPECT_EQ(report["range"], nlohmann::json::array({-100.0, 100.0}));
}

TEST_F(RenderCommand, BadInputExitsThreeNamesTheFileAndWritesNothing) {
  ExpectBadInput("render " + P("missing.ply") + " -o " + P("out.png"), "missing.ply", "");
  Write("broken.ply",
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
        "property float z\nend_header\n0 0 0\n1 1\n");
  ExpectBadInput("render " + P("broken.ply") + " -o " + P("out.png"), "broken.ply", "");
  Write("empty.ply",
        "ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\nproperty float z\n"
        "end_header\n");
  ExpectBadInput("render " + P("empty.ply") + " -o " + P("out.png"), "empty.ply", "no points to draw");
  Write("triangle.ply", kTriangle);
  ExpectBadInput("render " + P("triangle.ply") + " -o " + P("out.png") + " --scalar curvature",
                 "triangle.ply", "no per-vertex scalar 'curvature' (it has: none)");
}

TEST_F(RenderCommand, UsageErrorsExitTwoAndWriteNothing) {
  Write("square.ply", kSquare);
  EXPECT_EQ(Pectus("render " + P("square.ply") + " -o " + P("out.jpg")).code, 2) << "PNG only";
  EXPECT_EQ(
      Pectus("render " + P("square.ply") + " -o " + P("out.png") + " --scalar height_mm --range 5,1").code,
      2);
  EXPECT_EQ(Pectus("render " + P("square.ply") + " -o " + P("out.png") + " --view sideways").code, 2);
  EXPECT_EQ(CountFiles(), 1u) << "only the input is left";
}

}  // namespace
}  // namespace pectus
