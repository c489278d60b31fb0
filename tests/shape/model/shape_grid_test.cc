// The resampling grid: its size and parsing, its row and column positions over the ROI, its faces
// (count, orientation along the ROI normal, a consistently oriented manifold that tiles the rectangle),
// and shape vectors (Eq. 12) to and from vertices.
#include "shape/model/shape_grid.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <map>
#include <utility>

#include "shape/core/error.h"

namespace pectus {
namespace {

// A ROI in an oblique orthonormal frame (not the coordinate axes), 80 mm wide and 150 mm high.
ChestRoi ObliqueRoi() {
  const Eigen::Matrix3d R = (Eigen::AngleAxisd(0.4, Eigen::Vector3d(1, 2, 3).normalized()) *
                             Eigen::AngleAxisd(2.0, Eigen::Vector3d::UnitX()))
                                .toRotationMatrix();
  ChestRoi roi;
  roi.origin = Eigen::Vector3d(10, -100, 50);
  roi.lateral = R.col(0);
  roi.sternal = R.col(1);
  roi.normal = roi.sternal.cross(roi.lateral);
  roi.u_min = -40;
  roi.u_max = 40;
  roi.v_min = -10;
  roi.v_max = 140;
  return roi;
}

// The grid's vertices at their ROI positions (w = 0), row-major as GridSize::Index.
Points3 FlatGrid(const ChestRoi& roi, const GridSize& g) {
  const Eigen::VectorXd u = GridLateralPositions(roi, g), v = GridSternalPositions(roi, g);
  Points3 uvw(g.num_vertices(), 3);
  for (int i = 0; i < g.sternal; ++i) {
    for (int j = 0; j < g.lateral; ++j) uvw.row(g.Index(i, j)) << u[j], v[i], 0.0;
  }
  return roi.FromRoi(uvw);
}

TEST(ShapeGrid, DefaultIsTheDissertationsGrid) {
  const GridSize g;
  EXPECT_EQ(g.num_vertices(), 5151);
  EXPECT_EQ(3 * g.num_vertices(), 15453);
  EXPECT_EQ(g.Index(1, 0), 51);
  EXPECT_EQ(g.Index(100, 50), 5150);
  const GridSize p = ParseGridSize("11x21");
  EXPECT_EQ(p.lateral, 11);
  EXPECT_EQ(p.sternal, 21);
  EXPECT_EQ(ParseGridSize(" 7 X 9 ").lateral, 7);
  EXPECT_THROW(ParseGridSize("11by21"), Error);
  EXPECT_THROW(ParseGridSize("1x21"), Error);
  EXPECT_THROW(ParseGridSize("11x"), Error);
  EXPECT_THROW(ParseGridSize("1234567x2"), Error);
  std::string why;
  EXPECT_FALSE((GridSize{100001, 2}.IsValid(&why)));
  EXPECT_NE(why.find("100001x2"), std::string::npos) << why;
}

TEST(ShapeGrid, RowsAndColumnsSpanTheRoiEvenly) {
  const ChestRoi roi = ObliqueRoi();
  const GridSize g{5, 7};
  const Eigen::VectorXd u = GridLateralPositions(roi, g), v = GridSternalPositions(roi, g);
  ASSERT_EQ(u.size(), 5);
  ASSERT_EQ(v.size(), 7);
  for (int j = 0; j < 5; ++j) EXPECT_NEAR(u[j], -40.0 + 20.0 * j, 1e-12);
  for (int i = 0; i < 7; ++i) EXPECT_NEAR(v[i], -10.0 + 25.0 * i, 1e-12);
}

TEST(ShapeGrid, FacesTileTheRectangleFacingAlongTheRoiNormal) {
  const ChestRoi roi = ObliqueRoi();
  const GridSize g{5, 7};
  const Points3 x = FlatGrid(roi, g);
  const Faces3 f = GridFaces(g);
  // Two triangles per cell.
  ASSERT_EQ(f.rows(), 2 * 4 * 6);
  double area = 0;
  std::map<std::pair<int, int>, int> directed;  // each directed edge once: consistent orientation
  for (Eigen::Index k = 0; k < f.rows(); ++k) {
    const Eigen::Vector3d n =
        (x.row(f(k, 1)) - x.row(f(k, 0))).cross(x.row(f(k, 2)) - x.row(f(k, 0))).transpose();
    EXPECT_NEAR(n.normalized().dot(roi.normal), 1.0, 1e-12) << "face " << k;
    area += n.norm() / 2;
    for (int e = 0; e < 3; ++e) ++directed[{f(k, e), f(k, (e + 1) % 3)}];
  }
  // The triangles cover the 80 x 150 mm rectangle without overlap (they all face the same way).
  EXPECT_NEAR(area, 80.0 * 150.0, 1e-9);
  // A manifold, consistently oriented: no directed edge twice; interior edges used both ways; the
  // border edges (2 (4 + 6) of them) once.
  int border = 0;
  for (const auto& [edge, count] : directed) {
    EXPECT_EQ(count, 1);
    if (directed.count({edge.second, edge.first}) == 0) ++border;
  }
  EXPECT_EQ(border, 2 * (4 + 6));
  // Every vertex is used.
  Eigen::VectorXi used = Eigen::VectorXi::Zero(g.num_vertices());
  for (Eigen::Index k = 0; k < f.size(); ++k) used(f.data()[k]) = 1;
  EXPECT_EQ(used.sum(), g.num_vertices());
}

TEST(ShapeGrid, ShapeVectorsInterleaveCoordinatesAndRoundTrip) {
  const GridSize g{4, 3};
  const Points3 x = FlatGrid(ObliqueRoi(), g);
  const Eigen::VectorXd s = ToShapeVector(x);
  ASSERT_EQ(s.size(), 3 * g.num_vertices());
  // (x1, y1, z1, ..., xm, ym, zm), Eq. (12).
  for (Eigen::Index i = 0; i < x.rows(); ++i) {
    for (int c = 0; c < 3; ++c) EXPECT_EQ(s[3 * i + c], x(i, c));
  }
  EXPECT_EQ(FromShapeVector(s), x);
  EXPECT_EQ(ToShapeVector(FromShapeVector(s)), s);
  EXPECT_THROW(FromShapeVector(Eigen::VectorXd::Zero(10)), Error);
}

}  // namespace
}  // namespace pectus
