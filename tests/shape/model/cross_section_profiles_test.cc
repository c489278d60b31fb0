// The section profiles of an analytic chest: each row's and column's curve follows the true depth along
// its plane, and the blend of the two puts every grid vertex on the surface, also on a grid reaching
// beyond the ROI into the fit margin.
#include "shape/model/cross_section_profiles.h"

#include <gtest/gtest.h>

#include "analytic_chest.h"
#include "shape/model/cross_section_resampler.h"

namespace pectus {
namespace {

TEST(CrossSectionProfiles, RowAndColumnCurvesFollowTheTrueDepthAndTheirBlendLiesOnTheSurface) {
  const testing::AnalyticChest chest = testing::PlacedChest();
  const TriangleMesh mesh = chest.Mesh(-110.0, 110.0, -40.0, 220.0, 1.5);
  const ChestRoi roi = ComputeChestRoi(chest.Landmarks());
  // A 21 x 41 grid over the ROI grown by 20 mm on each side (inside the 25 mm fit margin).
  ChestRoi grown = roi;
  grown.u_min -= 20.0, grown.u_max += 20.0, grown.v_min -= 20.0, grown.v_max += 20.0;
  const GridSize grid{21, 41};
  const Eigen::VectorXd u = GridLateralPositions(grown, grid), v = GridSternalPositions(grown, grid);
  const CrossSectionOptions options;
  const SectionCurves curves = FitSectionCurves(mesh, roi, u, v, options);
  ASSERT_EQ(curves.rows.size(), 41u);
  ASSERT_EQ(curves.columns.size(), 21u);
  double worst_row = 0.0, worst_column = 0.0;
  for (int i = 0; i < grid.sternal; ++i) {
    for (int j = 0; j < grid.lateral; ++j) {
      ASSERT_TRUE(curves.rows[i].valid() && curves.columns[j].valid());
      const double truth = chest.TrueDepth(roi, u[j], v[i]);
      worst_row = std::max(worst_row, std::abs(curves.rows[i](u[j]) - truth));
      worst_column = std::max(worst_column, std::abs(curves.columns[j](v[i]) - truth));
    }
  }
  EXPECT_LT(worst_row, 0.05);
  EXPECT_LT(worst_column, 0.05);

  const ProfileRoughness rows = FamilyRoughness(curves.rows, u, options.fit.knot_spacing_mm);
  const ProfileRoughness columns = FamilyRoughness(curves.columns, v, options.fit.knot_spacing_mm);
  // Both families bend: across (radius 160 mm) and along (the dent).
  EXPECT_GT(rows.d4, 0.0);
  EXPECT_GT(columns.d4, 0.0);
  const BlendedGrid blend = BlendSectionCurves(curves, grid, u, v, rows, columns, 1e-4);
  for (int i = 0; i < grid.sternal; ++i) {
    for (int j = 0; j < grid.lateral; ++j) {
      const Eigen::Index k = grid.Index(i, j);
      ASSERT_TRUE(blend.known[k]);
      EXPECT_NEAR(blend.depth[k], chest.TrueDepth(roi, u[j], v[i]), 0.05);
      EXPECT_LT(blend.gap[k], 1.5);  // the mesh's spacing
    }
  }
}

TEST(CrossSectionProfiles, ProfilesOutsideTheDataAreLeftUnfitted) {
  const testing::AnalyticChest chest = testing::PlacedChest();
  // The surface covers only x in [-30, 30]: the outer columns' planes miss it.
  const TriangleMesh mesh = chest.Mesh(-30.0, 30.0, -40.0, 220.0, 1.5);
  const ChestRoi roi = ComputeChestRoi(chest.Landmarks());
  const GridSize grid{11, 21};
  const Eigen::VectorXd u = GridLateralPositions(roi, grid), v = GridSternalPositions(roi, grid);
  CrossSectionOptions options;
  options.directions = SectionDirections::kColumns;
  const SectionCurves curves = FitSectionCurves(mesh, roi, u, v, options);
  EXPECT_TRUE(curves.rows.empty());
  ASSERT_EQ(curves.columns.size(), 11u);
  EXPECT_FALSE(curves.columns.front().valid());
  EXPECT_FALSE(curves.columns.back().valid());
  EXPECT_TRUE(curves.columns[5].valid());
  const BlendedGrid blend = BlendSectionCurves(curves, grid, u, v, {}, {}, 1e-4);
  EXPECT_FALSE(blend.known[grid.Index(10, 0)]);
  EXPECT_TRUE(blend.known[grid.Index(10, 5)]);
  EXPECT_NEAR(blend.depth[grid.Index(10, 5)], chest.TrueDepth(roi, u[5], v[10]), 0.05);
}

}  // namespace
}  // namespace pectus
