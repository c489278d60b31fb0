// Tests of datasets/chest_surface: exact derivatives, the documented frame, growth and pose.
#include "datasets/chest_surface.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include "datasets/chest_population.h"
#include "shape/core/error.h"

namespace pectus::datasets {
namespace {

ChestParameters Sample(std::uint64_t seed) {
  return SampleSubject(PopulationModel::Default(), seed).parameters;
}

TEST(ChestSurface, DerivativesMatchCentralDifferences) {
  ChestParameters p = Sample(3);
  p.pectus.depth_mm = 30.0;
  p.pectus.type = PectusType::kCup;
  p.pectus.torsion_deg = 12.0;
  p.pectus.asymmetry = 0.3;
  const ChestSurface s(p);
  const double h = 1e-6;
  for (double u : {-0.9, -0.4, 0.0, 0.13, 0.6}) {
    for (double v : {0.05, 0.3, kVReference, 0.7, 0.95}) {
      const SurfacePoint sp = s.Evaluate(u, v);
      const Eigen::Vector3d du = (s.Position(u + h, v) - s.Position(u - h, v)) / (2 * h);
      const Eigen::Vector3d dv = (s.Position(u, v + h) - s.Position(u, v - h)) / (2 * h);
      // Central differences are exact to O(h^2) plus rounding ~1e-10 / h: 1e-3 mm per unit is ample.
      EXPECT_LT((sp.d_du - du).norm(), 1e-3) << u << " " << v;
      EXPECT_LT((sp.d_dv - dv).norm(), 1e-3) << u << " " << v;
      EXPECT_NEAR(sp.normal.norm(), 1.0, 1e-12);
      EXPECT_LT((sp.position - s.Position(u, v)).norm(), 1e-12);
    }
  }
}

TEST(ChestSurface, FrameIsLeftUpAnterior) {
  const ChestSurface s(PopulationModel::Default().mean);
  // The midline front faces +z; the subject's left (u > 0) is +x; the notch level is y = 0, the xiphoid y =
  // -L.
  EXPECT_GT(s.Evaluate(0.0, kVReference).normal.z(), 0.99);
  EXPECT_GT(s.Position(0.5, kVReference).x(), 50.0);
  EXPECT_LT(s.Position(-0.5, kVReference).x(), -50.0);
  EXPECT_NEAR(s.Position(0.0, kVNotch).y(), 0.0, 1e-9);
  EXPECT_NEAR(s.Position(0.3, kVXiphoid).y(), -s.parameters().sternal_length_mm, 1e-9);
  // At the mid-axillary lines the normal turns sideways.
  EXPECT_GT(s.Evaluate(1.0, kVReference).normal.x(), 0.9);
  EXPECT_LT(s.Evaluate(-1.0, kVReference).normal.x(), -0.9);
}

TEST(ChestSurface, SkinLiesOutsideTheChestWallByTheSoftTissue) {
  const ChestParameters p = PopulationModel::Default().mean;
  const ChestSurface skin(p), wall(p, Layer::kChestWall);
  // Laterally (u = +-0.85) no bulge reaches: the skin is the wall moved by the base thickness along n0.
  for (double u : {-0.85, 0.85}) {
    const double gap = (skin.Position(u, kVReference) - wall.Position(u, kVReference)).norm();
    EXPECT_NEAR(gap, p.soft_tissue_mm, 0.05);
  }
}

TEST(ChestSurface, GrowthAndPoseActAsDocumented) {
  ChestParameters p = Sample(5);
  const ChestSurface before(p);
  p.growth = Eigen::Vector3d(1.1, 1.2, 1.05);
  p.T_scan_subject =
      Eigen::Translation3d(10, -20, 30) * Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, 2, 3).normalized());
  const ChestSurface after(p);
  for (double u : {-0.7, 0.0, 0.4}) {
    for (double v : {0.2, 0.6}) {
      const Eigen::Vector3d expected = p.T_scan_subject * before.Position(u, v).cwiseProduct(p.growth);
      EXPECT_LT((after.Position(u, v) - expected).norm(), 1e-9);
      const Eigen::Vector2d guess = after.GuessParameters(after.Position(u, v));
      EXPECT_NEAR(guess.y(), v, 0.05);
    }
  }
}

TEST(ChestSurface, PectusDepthIsTheDeepestInwardDisplacement) {
  for (PectusType type : {PectusType::kSaucer, PectusType::kCup}) {
    ChestParameters p = PopulationModel::Default().mean;
    const ChestSurface flat(p, Layer::kChestWall);
    p.pectus.depth_mm = 40.0;
    p.pectus.type = type;
    p.pectus.torsion_deg = 20.0;
    const ChestSurface pe(p, Layer::kChestWall);
    double deepest = 0.0, deepest_u = 0.0;
    for (int i = 0; i <= 400; ++i) {
      for (int j = 0; j <= 200; ++j) {
        const double u = -1.0 + 2.0 * i / 400, v = 1.0 * j / 200;
        const double d = (flat.Position(u, v) - pe.Position(u, v)).norm();
        if (d > deepest) deepest = d, deepest_u = u;
      }
    }
    // Displacement is along the unit reference normal, so its length is the inward displacement (grid: 0.2
    // mm).
    EXPECT_NEAR(deepest, 40.0, 0.2) << ToString(type);
    EXPECT_LT(deepest_u, 0.0) << "positive torsion sinks the subject's right side (u < 0)";
  }
}

TEST(ChestSurface, RejectsInvalidParameters) {
  ChestParameters p;
  p.width_mm = 20.0;
  EXPECT_THROW(ChestSurface{p}, Error);
  p = ChestParameters();
  p.pectus.depth_mm = 75.0;
  EXPECT_THROW(ChestSurface{p}, Error);
}

}  // namespace
}  // namespace pectus::datasets
