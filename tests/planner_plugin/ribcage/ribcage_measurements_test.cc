// The CT measurements of a ribcage (width, depth, sternal length, depression, torsion, Haller index) on
// an analytic ribcage made of prisms whose every figure is known in closed form, apart from the generic
// ribcage and the patient fit that use the measurements.
#include "planner_plugin/ribcage/ribcage_measurements.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <vector>

#include "shape/core/error.h"

namespace pectus::planner {
namespace {

// LPS: x left, y posterior, z superior.
//  - The sternum (part 0): x in [-15, 15] (six 5 mm columns, so the measurement's middle band has
//    points), posterior surface y = 40, anterior surface y = front(z): 30 on a plateau z in [30, 50]
//    (the deepest depression, centred on the flat level 0.75 L from the notch), sloping forward by
//    0.5 mm per mm above and below; z from 0 (xiphoid) to kLength = 160 (notch).
//  - Four rib sections, 12 x 12 mm boxes through z in [-20, 180]: the outermost ribs (parts +1 and -1)
//    at |x| in [108, 120], y in [80, 92]; the most anterior costal cartilage (part +3) at x in [50, 62],
//    y in [0, 12]; a posterior rib (part +2) at x in [40, 52], y in [168, 180].
//  - The anterior surface of the spine at y = 150.
// On the plateau: width 240, depth 180 (y 0 to 180), depression 30 (the sternum's front at 30 behind
// the cartilage's at 0), inner width 216 (108 + 108), sternum to spine 110 (150 - 40), Haller index
// 216 / 110; sternal length 160; torsion 0.
constexpr double kLength = 160.0, kSpineY = 150.0, kBackY = 40.0;

double SternumFront(double z) {
  if (z > 50.0) return 30.0 - 0.5 * (z - 50.0);
  if (z < 30.0) return 30.0 - 0.5 * (30.0 - z);
  return 30.0;
}

// Appends the quad (a, b, c, d) as two triangles facing `outward`.
void AddQuad(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
             const Eigen::Vector3d& d, const Eigen::Vector3d& outward, int part,
             std::vector<Eigen::Vector3d>* v, std::vector<Eigen::Vector3i>* f, std::vector<int>* parts) {
  for (const auto& tri : {std::array<Eigen::Vector3d, 3>{a, b, c}, std::array<Eigen::Vector3d, 3>{a, c, d}}) {
    const auto n = static_cast<int>(v->size());
    for (const Eigen::Vector3d& p : tri) v->push_back(p);
    const bool flip = (tri[1] - tri[0]).cross(tri[2] - tri[0]).dot(outward) < 0;
    f->push_back(flip ? Eigen::Vector3i(n, n + 2, n + 1) : Eigen::Vector3i(n, n + 1, n + 2));
    parts->push_back(part);
  }
}

// A closed prism over the columns `xs` and the levels `zs`: front y = front(z) (planar between levels),
// back y = back.
template <typename Front>
void AddPrism(const std::vector<double>& xs, const std::vector<double>& zs, Front front, double back,
              int part, std::vector<Eigen::Vector3d>* v, std::vector<Eigen::Vector3i>* f,
              std::vector<int>* parts) {
  auto P = [](double x, double y, double z) { return Eigen::Vector3d(x, y, z); };
  const double x0 = xs.front(), x1 = xs.back();
  for (std::size_t j = 0; j + 1 < zs.size(); ++j) {
    const double za = zs[j], zb = zs[j + 1], ya = front(za), yb = front(zb);
    for (std::size_t i = 0; i + 1 < xs.size(); ++i) {
      const double xa = xs[i], xb = xs[i + 1];
      AddQuad(P(xa, ya, za), P(xb, ya, za), P(xb, yb, zb), P(xa, yb, zb), -Eigen::Vector3d::UnitY(), part, v,
              f, parts);
      AddQuad(P(xa, back, za), P(xb, back, za), P(xb, back, zb), P(xa, back, zb), Eigen::Vector3d::UnitY(),
              part, v, f, parts);
    }
    AddQuad(P(x0, ya, za), P(x0, back, za), P(x0, back, zb), P(x0, yb, zb), -Eigen::Vector3d::UnitX(), part,
            v, f, parts);
    AddQuad(P(x1, ya, za), P(x1, back, za), P(x1, back, zb), P(x1, yb, zb), Eigen::Vector3d::UnitX(), part, v,
            f, parts);
  }
  for (std::size_t i = 0; i + 1 < xs.size(); ++i) {
    for (const double z : {zs.front(), zs.back()}) {
      const Eigen::Vector3d out = (z == zs.front() ? -1.0 : 1.0) * Eigen::Vector3d::UnitZ();
      AddQuad(P(xs[i], front(z), z), P(xs[i + 1], front(z), z), P(xs[i + 1], back, z), P(xs[i], back, z), out,
              part, v, f, parts);
    }
  }
}

RibcageSurface AnalyticRibcage() {
  std::vector<Eigen::Vector3d> v;
  std::vector<Eigen::Vector3i> f;
  std::vector<int> parts;
  AddPrism({-15, -10, -5, 0, 5, 10, 15}, {0, 30, 50, kLength}, SternumFront, kBackY, 0, &v, &f, &parts);
  struct Box {
    double x0, y0;
    int part;
  };
  for (const Box& b : {Box{108, 80, 1}, Box{-120, 80, -1}, Box{50, 0, 3}, Box{40, 168, 2}}) {
    AddPrism(
        {b.x0, b.x0 + 12}, {-20, 180}, [&](double) { return b.y0; }, b.y0 + 12, b.part, &v, &f, &parts);
  }
  RibcageSurface s;
  s.nodes.resize(static_cast<Eigen::Index>(v.size()), 3);
  for (std::size_t i = 0; i < v.size(); ++i) s.nodes.row(static_cast<Eigen::Index>(i)) = v[i].transpose();
  s.faces.resize(static_cast<Eigen::Index>(f.size()), 3);
  for (std::size_t i = 0; i < f.size(); ++i) s.faces.row(static_cast<Eigen::Index>(i)) = f[i].transpose();
  s.face_parts = Eigen::Map<const Eigen::VectorXi>(parts.data(), static_cast<Eigen::Index>(parts.size()));
  s.spine_anterior.resize(2, 3);
  s.spine_anterior << 0, kSpineY, 200, 0, kSpineY, -50;
  return s;
}

// Every figure is read off straight segments and planar faces cut at a plateau level: exact but for
// round-off (1e-9 mm); the slice level is a soft maximum symmetric about the plateau's centre, so it
// lands there to round-off too (1e-6 mm allows for the accumulated slice grid).
TEST(RibcageMeasurements, AnalyticRibcageMeasuresItsClosedFormFigures) {
  const RibcageMeasurements m = MeasureRibcage(AnalyticRibcage());
  EXPECT_NEAR(m.notch_z_mm, kLength, 1e-9);
  EXPECT_NEAR(m.sternal_length_mm, kLength, 1e-9);
  EXPECT_NEAR(m.slice_z_mm, 40.0, 1e-6);
  EXPECT_NEAR(m.width_mm, 240.0, 1e-9);
  EXPECT_NEAR(m.depth_mm, 180.0, 1e-9);
  EXPECT_NEAR(m.depression_mm, 30.0, 1e-9);
  EXPECT_NEAR(m.torsion_deg, 0.0, 1e-9);
  EXPECT_NEAR(m.inner_width_mm, 216.0, 1e-9);
  EXPECT_NEAR(m.sternum_to_spine_mm, kSpineY - kBackY, 1e-9);
  EXPECT_NEAR(m.haller_index, 216.0 / 110.0, 1e-12);
}

TEST(RibcageMeasurements, DepressionProfileFollowsTheSternumsFront) {
  // Per slice: the sternum's front behind the cartilage's (y = 0), or 0 where the sternum is in front.
  const auto profile = DepressionProfile(AnalyticRibcage());
  ASSERT_GT(profile.size(), 100u);  // 0.3 to 0.95 of 160 mm in 0.5 mm steps: 209 slices
  for (const auto& [z, depression] : profile) {
    EXPECT_NEAR(depression, std::max(SternumFront(z), 0.0), 1e-9) << "z = " << z;
  }
}

TEST(RibcageMeasurements, TwistedSternumMeasuresItsTorsion) {
  // The sternum turned by 10 degrees about its vertical axis through (0, 35), its right edge (x < 0)
  // going posterior (+y): torsion +10 degrees, from the section's principal axis.
  RibcageSurface s = AnalyticRibcage();
  const double a = 10.0 * std::numbers::pi / 180.0;
  for (Eigen::Index f = 0; f < s.faces.rows(); ++f) {
    if (s.face_parts(f) != 0) continue;
    for (int k = 0; k < 3; ++k) {
      auto p = s.nodes.row(s.faces(f, k));
      const double x = p(0), y = p(1) - 35.0;
      // Each face has its own vertices (AddQuad), so every sternum vertex is turned exactly once.
      p(0) = std::cos(a) * x + std::sin(a) * y;
      p(1) = 35.0 - std::sin(a) * x + std::cos(a) * y;
    }
  }
  EXPECT_NEAR(MeasureRibcage(s).torsion_deg, 10.0, 1e-9);
}

TEST(RibcageMeasurements, MissingPartsAreBadInput) {
  RibcageSurface s = AnalyticRibcage();
  s.face_parts.setConstant(1);  // no sternum
  EXPECT_THROW(MeasureRibcage(s), Error);
  RibcageSurface short_spine = AnalyticRibcage();
  short_spine.spine_anterior << 0, kSpineY, 200, 0, kSpineY, 150;  // ends above the slice
  EXPECT_THROW(MeasureRibcage(short_spine), Error);
  RibcageMeasurementOptions bad;
  bad.search_from = 0.9;
  bad.search_to = 0.5;
  EXPECT_THROW(MeasureRibcage(AnalyticRibcage(), bad), Error);
}

}  // namespace
}  // namespace pectus::planner
