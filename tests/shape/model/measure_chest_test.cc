// Chest measures on analytic chests: the straight-edge depth of a Gaussian dent on a frontal surface, and
// the external Haller and correction indices of a closed elliptic torso with a dent.
#include "shape/model/measure_chest.h"

#include <gtest/gtest.h>

#include <cmath>

#include "shape/core/error.h"

namespace pectus {
namespace {

constexpr double kPi = 3.14159265358979323846;

// The pectus frame (x to the subject's left, y up, z anterior) with landmarks that make the ROI frame
// u = x, v = -y (down the sternum), w = z - z0 (anterior).
ChestRoi AlignedRoi(double z0) {
  LandmarkSet s;
  s.items.push_back({"sternal_notch", {0, 0, z0}, ""});
  s.items.push_back({"xiphoid", {0, -180, z0}, ""});
  s.items.push_back({"costal_cartilage_1_left", {45, -15, z0}, ""});
  ChestRoiOptions o;
  o.anterior_hint = Eigen::Vector3d::UnitZ();
  return ComputeChestRoi(s, o);
}

// A Gaussian depression 15 mm deep, 110 mm below the notch (y = -110).
double Dent(double x, double y) {
  return 15.0 * std::exp(-(x * x + (y + 110.0) * (y + 110.0)) / (2.0 * 25.0 * 25.0));
}

TEST(ChestMeasures, StraightEdgeDepthOfAGaussianDent) {
  // Frontal surface z = -x^2 / 320 - dent, x in [-120, 120], y in [-200, 20].
  auto f = [](double x, double y) { return -x * x / 320.0 - Dent(x, y); };
  const int nx = 161, ny = 147;
  TriangleMesh m;
  m.vertices.positions.resize(nx * ny, 3);
  for (int j = 0; j < ny; ++j) {
    for (int i = 0; i < nx; ++i) {
      const double x = -120.0 + 1.5 * i, y = -200.0 + 1.5 * j;
      m.vertices.positions.row(j * nx + i) << x, y, f(x, y);
    }
  }
  m.faces.resize(2 * (nx - 1) * (ny - 1), 3);
  int k = 0;
  for (int j = 0; j + 1 < ny; ++j) {
    for (int i = 0; i + 1 < nx; ++i) {
      const int a = j * nx + i;
      m.faces.row(k++) << a, a + 1, a + nx;
      m.faces.row(k++) << a + 1, a + nx + 1, a + nx;
    }
  }
  // Expected: at y = -110 the edge rests on the two symmetric crests; depth = crest - centre.
  double crest = -1e9;
  for (double x = 0.0; x < 120.0; x += 0.001) crest = std::max(crest, f(x, -110.0));
  const double expected = crest - f(0.0, -110.0);  // about 5.8 mm
  const ChestMeasures c = MeasureChest(m, AlignedRoi(0.0));
  EXPECT_NEAR(c.depression_depth_mm, expected, 0.05);
  EXPECT_NEAR(c.depression_level_mm, 110.0, 1.0);
  EXPECT_NEAR(c.depression_lateral_mm, 0.0, 1.0);
  EXPECT_FALSE(c.closed_section);
  EXPECT_TRUE(std::isnan(c.external_haller_index));
  EXPECT_TRUE(c.ToJson()["external_haller_index"].is_null());
}

TEST(ChestMeasures, ExternalIndicesOfAClosedTorso) {
  // Elliptic torso: x = 140 cos t, z = 100 sin t - dent (front half only), y in [-200, 20].
  const double a = 140.0, b = 100.0;
  const int nt = 720, ny = 111;
  auto point = [&](double t, double y) {
    const double x = a * std::cos(t), s = std::max(0.0, std::sin(t));
    return Eigen::Vector3d(x, y, b * std::sin(t) - s * s * Dent(x, y));
  };
  TriangleMesh m;
  m.vertices.positions.resize(nt * ny, 3);
  for (int j = 0; j < ny; ++j) {
    for (int i = 0; i < nt; ++i)
      m.vertices.positions.row(j * nt + i) = point(2 * kPi * i / nt, -200.0 + 2.0 * j).transpose();
  }
  m.faces.resize(2 * nt * (ny - 1), 3);
  int k = 0;
  for (int j = 0; j + 1 < ny; ++j) {
    for (int i = 0; i < nt; ++i) {
      const int p = j * nt + i, q = j * nt + (i + 1) % nt;
      m.faces.row(k++) << p, p + nt, q;
      m.faces.row(k++) << q, p + nt, q + nt;
    }
  }
  double front = -1e9;
  for (double t = 0.0; t < kPi; t += 1e-5) front = std::max(front, point(t, -110.0).z());
  const double ap_min = (b - Dent(0.0, -110.0)) + b, ap_max = front + b;
  const ChestMeasures c = MeasureChest(m, AlignedRoi(b));
  ASSERT_TRUE(c.closed_section);
  EXPECT_NEAR(c.depression_level_mm, 110.0, 1.0);
  EXPECT_NEAR(c.chest_width_mm, 2.0 * a, 0.01);
  EXPECT_NEAR(c.ap_depth_min_mm, ap_min, 0.05);
  EXPECT_NEAR(c.ap_depth_max_mm, ap_max, 0.05);
  EXPECT_NEAR(c.external_haller_index, 2.0 * a / ap_min, 0.002);
  EXPECT_NEAR(c.external_correction_index_pct, 100.0 * (ap_max - ap_min) / ap_max, 0.05);
}

TEST(ChestMeasures, NeedsAMeshThatReachesBothSides) {
  TriangleMesh points;
  points.vertices.positions = Points3::Random(10, 3);
  EXPECT_THROW(MeasureChest(points, AlignedRoi(0.0)), Error);
  ChestMeasuresOptions o;
  o.levels = 1;
  EXPECT_FALSE(o.IsValid(nullptr));
}

}  // namespace
}  // namespace pectus
