// Cross-section resampling of an analytic chest (known depth at every grid vertex) placed at an arbitrary
// pose: mesh and point-cloud input, polynomial and spline profiles, extrapolation beyond the data, errors.
#include "shape/model/cross_section_resampler.h"

#include <gtest/gtest.h>

#include "analytic_chest.h"
#include "shape/core/error.h"

namespace pectus {
namespace {

using testing::AnalyticChest;
using testing::PlacedChest;

// Largest |resampled depth - true depth| over the grid.
double WorstDepthError(const AnalyticChest& chest, const CrossSectionResult& r) {
  const Eigen::VectorXd u = GridLateralPositions(r.roi, r.grid), v = GridSternalPositions(r.roi, r.grid);
  const Eigen::VectorXd& w = r.mesh.vertices.scalars.at("depth_mm");
  double worst = 0.0;
  for (int i = 0; i < r.grid.sternal; ++i) {
    for (int j = 0; j < r.grid.lateral; ++j) {
      worst = std::max(worst, std::abs(w[r.grid.Index(i, j)] - chest.TrueDepth(r.roi, u[j], v[i])));
    }
  }
  return worst;
}

TEST(CrossSectionResampler, SplineResamplesAnAnalyticChestWithinTwentiethOfAMillimetre) {
  const AnalyticChest chest = PlacedChest();
  const TriangleMesh mesh = chest.Mesh(-110.0, 110.0, -40.0, 220.0, 1.5);
  const CrossSectionResult r = ResampleSurface(mesh, chest.Landmarks());
  ASSERT_EQ(r.mesh.num_vertices(), 5151);
  ASSERT_EQ(r.shape_vector.size(), 15453);
  EXPECT_EQ(r.profiles_unfitted, 0);
  EXPECT_LT(WorstDepthError(chest, r), 0.05);
  EXPECT_DOUBLE_EQ(r.supported_fraction, 1.0);
  // The ROI plane passes through the three landmarks and faces the chest's anterior (+z of its frame).
  const Eigen::Vector3d n = chest.T_world_chest.rotation.transpose() * r.roi.normal;
  const Eigen::Vector3d notch(0.0, 0.0, chest.f(0.0, 0.0)), xiphoid(0.0, -180.0, chest.f(0.0, 180.0)),
      cartilage(45.0, -15.0, chest.f(45.0, 15.0));
  EXPECT_NEAR(n.dot((xiphoid - notch).normalized()), 0.0, 1e-9);
  EXPECT_NEAR(n.dot((cartilage - notch).normalized()), 0.0, 1e-9);
  EXPECT_GT(n.z(), 0.9);
  // The vertices lie on the surface: their depth in the chest frame matches f.
  const Similarity3 T = chest.T_world_chest.Inverse();
  for (Eigen::Index k = 0; k < r.mesh.num_vertices(); k += 97) {
    const Eigen::Vector3d p = T * Eigen::Vector3d(r.mesh.vertices.positions.row(k).transpose());
    EXPECT_NEAR(p.z(), chest.f(p.x(), -p.y()), 0.05);
  }
}

TEST(CrossSectionResampler, PolynomialProfilesAreLessAccurateOnTheDent) {
  const AnalyticChest chest = PlacedChest();
  const TriangleMesh mesh = chest.Mesh(-110.0, 110.0, -40.0, 220.0, 1.5);
  CrossSectionOptions o;
  o.fit.kind = ProfileFitKind::kPolynomial;
  o.fit.polynomial_degree = 8;
  const CrossSectionResult poly = ResampleSurface(mesh, chest.Landmarks(), {}, o);
  const CrossSectionResult spline = ResampleSurface(mesh, chest.Landmarks());
  const double e_poly = WorstDepthError(chest, poly), e_spline = WorstDepthError(chest, spline);
  EXPECT_LT(e_poly, 1.0);
  EXPECT_LT(e_spline, e_poly);
}

TEST(CrossSectionResampler, PointCloudInputMatchesTheMesh) {
  const AnalyticChest chest = PlacedChest();
  TriangleMesh cloud = chest.Mesh(-110.0, 110.0, -40.0, 220.0, 0.5);
  cloud.faces.resize(0, 3);
  CrossSectionOptions o;
  o.grid = GridSize{21, 41};
  const CrossSectionResult r = ResampleSurface(cloud, chest.Landmarks(), {}, o);
  // Slab sections of half-width 0.75 mm blur the profile a little.
  EXPECT_LT(WorstDepthError(chest, r), 0.15);
}

TEST(CrossSectionResampler, ExtrapolatesBeyondTheEdgeOfTheScan) {
  // The scan stops 8 mm short of the ROI on the right and the first 10 mm below the notch are missing.
  const AnalyticChest chest = PlacedChest();
  const TriangleMesh mesh = chest.Mesh(-37.0, 110.0, 10.0, 220.0, 1.5);
  CrossSectionOptions o;
  o.grid = GridSize{31, 61};
  const CrossSectionResult r = ResampleSurface(mesh, chest.Landmarks(), {}, o);
  EXPECT_GT(r.max_data_gap_mm, 7.0);
  EXPECT_LT(r.supported_fraction, 1.0);
  EXPECT_LT(WorstDepthError(chest, r), 0.5);
}

TEST(CrossSectionResampler, ASurfaceThatMissesTheRoiIsBadInput) {
  const AnalyticChest chest = PlacedChest();
  const TriangleMesh far = chest.Mesh(300.0, 400.0, 300.0, 400.0, 5.0);
  try {
    ResampleSurface(far, chest.Landmarks(), {}, {}, "far.ply");
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::kBadInput);
    EXPECT_NE(std::string(e.what()).find("far.ply"), std::string::npos);
  }
  CrossSectionOptions bad;
  bad.grid.lateral = 1;
  EXPECT_FALSE(bad.IsValid(nullptr));
  EXPECT_THROW(ResampleSurface(far, chest.Landmarks(), {}, bad), Error);
}

TEST(CrossSectionResampler, RowsOrColumnsAloneAlsoWork) {
  const AnalyticChest chest = PlacedChest();
  const TriangleMesh mesh = chest.Mesh(-110.0, 110.0, -40.0, 220.0, 1.5);
  for (auto d : {SectionDirections::kRows, SectionDirections::kColumns}) {
    CrossSectionOptions o;
    o.directions = d;
    o.grid = GridSize{21, 41};
    EXPECT_LT(WorstDepthError(chest, ResampleSurface(mesh, chest.Landmarks(), {}, o)), 0.05) << ToString(d);
  }
}

}  // namespace
}  // namespace pectus
