// Hole filling (dissertation §5.1): regions of 30 mm removed inside the ROI and across its border are
// rebuilt within 0.5 mm of the untouched surface and of the analytic truth; across the border in 2D where
// the data go on beyond it, with the profiles where the scan ends.
#include "shape/model/hole_fill_validation.h"

#include <gtest/gtest.h>

#include <random>

#include "analytic_chest.h"
#include "shape/core/error.h"

namespace pectus {
namespace {

TEST(HoleFill, ThirtyMillimetreHolesInsideAndAtTheBorderAreFilledWithinHalfAMillimetre) {
  const testing::AnalyticChest chest = testing::PlacedChest();
  const TriangleMesh mesh = chest.Mesh(-110.0, 110.0, -40.0, 220.0, 1.5);
  const ChestRoi roi = ComputeChestRoi(chest.Landmarks());
  const std::vector<RemovedDisk> disks = DefaultRemovedDisks(roi, 15.0);
  const HoleFillResult r = ValidateHoleFill(mesh, roi, disks);
  EXPECT_LT(r.holed_surface.num_faces(), mesh.num_faces());
  EXPECT_GT(r.vertices_in_disks, 100);
  EXPECT_LT(r.max_error_in_disks_mm, 0.5);
  EXPECT_LT(r.max_error_mm, 0.5);
  // And against the truth.
  const Eigen::VectorXd u = GridLateralPositions(roi, r.holed.grid),
                        v = GridSternalPositions(roi, r.holed.grid);
  const Eigen::VectorXd& w = r.holed.mesh.vertices.scalars.at("depth_mm");
  double worst = 0.0;
  for (int i = 0; i < r.holed.grid.sternal; ++i) {
    for (int j = 0; j < r.holed.grid.lateral; ++j) {
      worst = std::max(worst, std::abs(w[r.holed.grid.Index(i, j)] - chest.TrueDepth(roi, u[j], v[i])));
    }
  }
  EXPECT_LT(worst, 0.5);
}

// Max |grid depth - true depth| over the grid vertices inside `disk`.
double MaxErrorInDisk(const testing::AnalyticChest& chest, const ChestRoi& roi, const CrossSectionResult& r,
                      const RemovedDisk& disk) {
  const Eigen::VectorXd u = GridLateralPositions(roi, r.grid), v = GridSternalPositions(roi, r.grid);
  const Eigen::VectorXd& w = r.mesh.vertices.scalars.at("depth_mm");
  double worst = 0.0;
  for (int i = 0; i < r.grid.sternal; ++i) {
    for (int j = 0; j < r.grid.lateral; ++j) {
      if (std::hypot(u[j] - disk.u, v[i] - disk.v) > disk.radius_mm) continue;
      worst = std::max(worst, std::abs(w[r.grid.Index(i, j)] - chest.TrueDepth(roi, u[j], v[i])));
    }
  }
  return worst;
}

TEST(HoleFill, ThirtyMillimetreHoleOverTheSternalGrooveIsFilledInTwoDimensions) {
  // A groove 4 mm deep along the sternum, Gaussian across it with sigma 8 mm (as the virtual scanner's
  // chests): narrower than the hole, so a row profile across the hole cannot see it.
  testing::AnalyticChest chest = testing::PlacedChest();
  chest.groove_depth = 4.0;
  chest.groove_sigma = 8.0;
  const TriangleMesh mesh = chest.Mesh(-110.0, 110.0, -40.0, 220.0, 1.5);
  const ChestRoi roi = ComputeChestRoi(chest.Landmarks());
  const RemovedDisk hole{0.0, 0.5 * (roi.v_min + roi.v_max), 15.0};
  const TriangleMesh holed = RemoveDisks(mesh, roi, {hole});
  const CrossSectionResult filled = ResampleCrossSections(holed, roi);
  EXPECT_GT(filled.vertices_inpainted, 50);
  EXPECT_LT(MaxErrorInDisk(chest, roi, filled, hole), 0.15);  // 0.05 mm measured
  // An isotropic thin plate cannot carry the groove across: it fills it in (0.89 mm measured).
  CrossSectionOptions isotropic;
  isotropic.holes.inpainting.stretch = 1.0;
  EXPECT_GT(MaxErrorInDisk(chest, roi, ResampleCrossSections(holed, roi, isotropic), hole), 0.5);
}

// Adds to every vertex coordinate a deterministic uniform noise in [-amplitude, amplitude] (mm).
void AddNoise(double amplitude, TriangleMesh* mesh) {
  std::mt19937 rng(3);
  for (Eigen::Index k = 0; k < mesh->vertices.positions.rows(); ++k) {
    for (int c = 0; c < 3; ++c)
      mesh->vertices.positions(k, c) += amplitude * (2.0 * static_cast<double>(rng()) / 4294967296.0 - 1.0);
  }
}

TEST(HoleFill, NoisyHoleAcrossTheBorderIsFilledInTwoDimensionsWhereTheDataGoOnBeyondIt) {
  // The scan goes on 65 mm beyond the ROI's left border (u = -45 mm); a 30 mm hole is centred on it.
  const testing::AnalyticChest chest = testing::PlacedChest();
  TriangleMesh mesh = chest.Mesh(-110.0, 110.0, -40.0, 220.0, 1.5);
  AddNoise(0.05, &mesh);
  const ChestRoi roi = ComputeChestRoi(chest.Landmarks());
  const RemovedDisk hole{roi.u_min, roi.v_min + roi.height() / 3.0, 15.0};
  const TriangleMesh holed = RemoveDisks(mesh, roi, {hole});
  // On the grid grown by the fit margin the hole lies inside and is filled in 2D.
  const CrossSectionResult filled = ResampleCrossSections(holed, roi);
  EXPECT_GT(filled.vertices_inpainted, 50);
  const double error_2d = MaxErrorInDisk(chest, roi, filled, hole);
  EXPECT_LT(error_2d, 0.12);  // 0.079 mm measured
  // On the ROI's grid alone the hole reaches the grid's border and keeps the row/column profiles, which
  // bridge 30 mm with the noise of the data at both ends (0.190 mm measured).
  CrossSectionOptions roi_only;
  roi_only.extend_grid = false;
  const CrossSectionResult profiles = ResampleCrossSections(holed, roi, roi_only);
  EXPECT_EQ(profiles.vertices_inpainted, 0);
  EXPECT_GT(MaxErrorInDisk(chest, roi, profiles, hole), 1.5 * error_2d);
}

TEST(HoleFill, HoleWhereTheScanEndsAtTheBorderKeepsTheProfiles) {
  // The scan ends 2 mm beyond the ROI's left border: the hole reaches past the data on the grown grid too.
  const testing::AnalyticChest chest = testing::PlacedChest();
  const TriangleMesh mesh = chest.Mesh(-47.0, 110.0, -40.0, 220.0, 1.5);
  const ChestRoi roi = ComputeChestRoi(chest.Landmarks());
  const RemovedDisk hole{roi.u_min, roi.v_min + roi.height() / 3.0, 15.0};
  const CrossSectionResult r = ResampleCrossSections(RemoveDisks(mesh, roi, {hole}), roi);
  EXPECT_EQ(r.vertices_inpainted, 0);
  EXPECT_LT(MaxErrorInDisk(chest, roi, r, hole), 0.1);  // 0.025 mm measured
}

TEST(HoleFill, RemoveDisksDropsTheFacesInsideAndKeepsTheRest) {
  const testing::AnalyticChest chest;
  const TriangleMesh mesh = chest.Mesh(-50.0, 50.0, -10.0, 190.0, 2.0);
  const ChestRoi roi = ComputeChestRoi(chest.Landmarks());
  const TriangleMesh holed = RemoveDisks(mesh, roi, {{0.0, 90.0, 10.0}});
  const Points3 uvw = roi.ToRoi(holed.vertices.positions);
  for (Eigen::Index k = 0; k < uvw.rows(); ++k) {
    EXPECT_GT(std::hypot(uvw(k, 0), uvw(k, 1) - 90.0), 10.0 - 1e-9);
  }
  EXPECT_GT(holed.num_faces(), mesh.num_faces() - 400);
  EXPECT_LT(holed.num_faces(), mesh.num_faces() - 100);
  holed.Validate("holed");
  EXPECT_THROW(ValidateHoleFill(mesh, roi, {}), Error);
}

}  // namespace
}  // namespace pectus
