// Hole filling (dissertation §5.1): regions of 30 mm removed inside the ROI and across its border are
// rebuilt within 0.5 mm of the untouched surface and of the analytic truth.
#include "shape/model/hole_fill_validation.h"

#include <gtest/gtest.h>

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
