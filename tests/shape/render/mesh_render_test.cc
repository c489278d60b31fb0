// Software rendering: framing, z-buffer order and shading, checked pixel by pixel.
#include "shape/render/mesh_render.h"

#include <gtest/gtest.h>

namespace pectus::render {
namespace {

// A square [x0, x0+s] x [y0, y0+s] at height z, facing +z.
TriangleMesh Square(double x0, double y0, double s, double z) {
  TriangleMesh m;
  m.vertices.positions.resize(4, 3);
  m.vertices.positions << x0, y0, z, x0 + s, y0, z, x0 + s, y0 + s, z, x0, y0 + s, z;
  m.faces.resize(2, 3);
  m.faces << 0, 1, 2, 0, 2, 3;
  return m;
}

TEST(RenderMesh, SquareFillsTheFramedPictureWithTheBaseColour) {
  View v = View::Front(100, 100);
  v.margin = 0.1;
  const Image im = RenderMesh(Square(0, 0, 10, 0), v);
  // Facing the camera, the headlight gives full brightness: the base colour exactly.
  const Rgb c = im.at(50, 50);
  EXPECT_EQ(c.r, v.base_colour.r);
  EXPECT_EQ(c.g, v.base_colour.g);
  EXPECT_EQ(c.b, v.base_colour.b);
  // The square spans pixels 10..89 (10 % margin on each side); outside is background.
  EXPECT_EQ(im.at(5, 50).r, 255);
  EXPECT_EQ(im.at(94, 50).r, 255);
  EXPECT_EQ(im.at(12, 50).r, v.base_colour.r);
  EXPECT_EQ(im.at(87, 50).r, v.base_colour.r);
}

TEST(RenderMesh, NearerSurfaceHidesFartherOneWhicheverIsDrawnFirst) {
  for (int order = 0; order < 2; ++order) {
    TriangleMesh near = Square(0, 0, 10, 5), far = Square(0, 0, 10, -5);
    TriangleMesh both;
    const TriangleMesh& first = order == 0 ? near : far;
    const TriangleMesh& second = order == 0 ? far : near;
    both.vertices = first.vertices;
    both.vertices.Append(second.vertices);
    both.faces.resize(4, 3);
    both.faces << first.faces, (second.faces.array() + 4).matrix();
    Colors3 colors(8, 3);
    for (int i = 0; i < 8; ++i) {
      const bool is_near = (order == 0) == (i < 4);
      colors.row(i) << (is_near ? 255 : 0), 0, (is_near ? 0 : 255);
    }
    View v = View::Front(64, 64);
    v.shading = false;
    const Image im = RenderMesh(both, v, &colors);
    EXPECT_EQ(im.at(32, 32).r, 255) << "order " << order;
    EXPECT_EQ(im.at(32, 32).b, 0) << "order " << order;
  }
}

TEST(RenderMesh, SharedFrameKeepsScaleBetweenPictures) {
  View v = View::Front(100, 100);
  v.margin = 0;
  Bounds3 frame;
  frame.min = {0, 0, 0};
  frame.max = {20, 20, 0};
  v.frame = frame;
  // A 10 mm square in a 20 mm frame covers the lower-left quarter of the picture.
  const Image im = RenderMesh(Square(0, 0, 10, 0), v);
  EXPECT_NE(im.at(25, 75).r, 255);
  EXPECT_EQ(im.at(75, 25).r, 255);
  EXPECT_EQ(im.at(75, 75).r, 255);
}

TEST(RenderMesh, ObliqueLightingDarkensTiltedSurface) {
  View v = View::Oblique(60, 0, 64, 64);
  v.shading = true;
  const Image im = RenderMesh(Square(0, 0, 10, 0), v);
  // Lambert: 0.3 + 0.7 cos 60 deg = 0.65 of the base colour.
  EXPECT_NEAR(im.at(32, 32).r, 0.65 * v.base_colour.r, 1.0);
}

TEST(RenderPoints, PointsLandWhereProjected) {
  PointCloud cloud;
  cloud.positions.resize(2, 3);
  cloud.positions << 0, 0, 0, 10, 10, 0;
  View v = View::Front(101, 101);
  v.margin = 0;
  v.point_radius = 0;
  const Image im = RenderPoints(cloud, v);
  EXPECT_NE(im.at(0, 100).r, 255);  // (0, 0) at the bottom left
  EXPECT_NE(im.at(100, 0).r, 255);  // (10, 10) at the top right
  EXPECT_EQ(im.at(50, 50).r, 255);
}

}  // namespace
}  // namespace pectus::render
