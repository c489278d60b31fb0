#include "planner_plugin/ribcage/ribcage_fem.h"

#include <gtest/gtest.h>

#include "planner_plugin/fem/surface_load.h"
#include "shape/core/error.h"
#include "tests/planner_plugin/ribcage/coarse_patient.h"
#include "tests/planner_plugin/ribcage/direct_lift.h"

namespace pectus::planner {
namespace {

// Patient 57 on a coarser mesh than the default (10 mm cells), to keep the test quick.
class RibcageFemTest : public testing::CoarsePatient57Test {};

TEST_F(RibcageFemTest, TwentyFourLoadCasesOnOneFactorisation) {
  const std::vector<BarLoad> loads = DissertationLoadCases();
  ASSERT_EQ(loads.size(), 24u);
  const std::vector<BarResult> results = fem_->Solve(loads);
  ASSERT_EQ(results.size(), 24u);
  EXPECT_EQ(fem_->solver().factorization().factorizations(), 1);
  for (std::size_t i = 0; i < results.size(); ++i) {
    const BarResult& r = results[i];
    EXPECT_GT(r.sternum_lift_mm, 0.0) << r.load.Name();
    EXPECT_GE(r.contact_faces, 8) << r.load.Name();
    // The patch is the bar's width across the sternum's back: 12 mm x 20-40 mm.
    EXPECT_GT(r.contact_area_mm2, 12.0 * 15.0) << r.load.Name();
    EXPECT_LT(r.contact_area_mm2, 2.0 * 12.0 * 45.0) << r.load.Name();
    // Linear: lift proportional to force at each position.
    const BarResult& first = results[i - i % 8];
    EXPECT_NEAR(r.sternum_lift_mm / first.sternum_lift_mm, r.load.force_n / first.load.force_n, 1e-9);
  }
  // The rib heads do not move.
  for (std::int32_t n : patient_->fixed_nodes) ASSERT_EQ(results[23].displacement.row(n).norm(), 0.0);
}

TEST_F(RibcageFemTest, ReactionsAtTheSpineBalanceTheBar) {
  const BarLoad bar{0.75, false, 400.0};
  LoadCase load{"bar", fem_->NodalForces(bar), {}};
  EXPECT_NEAR(load.nodal_forces.reshaped(3, load.nodal_forces.size() / 3).rowwise().sum()(1), -400.0, 1e-9);
  const Points3 u = fem_->solver().Solve({load}).front();
  const Eigen::VectorXd r = fem_->solver().Reactions(u, load);
  Eigen::Vector3d total = Eigen::Vector3d::Zero();
  const auto& prescribed = fem_->solver().partition().prescribed;
  for (std::size_t k = 0; k < prescribed.size(); ++k)
    total(prescribed[k] % 3) += r(static_cast<Eigen::Index>(k));
  EXPECT_LT((total - Eigen::Vector3d(0, 400.0, 0)).norm(), 1e-6 * 400.0) << total.transpose();
}

TEST_F(RibcageFemTest, ForceToLiftTheSternumByItsDepression) {
  const std::vector<ForceToLift> f =
      fem_->ForceToLiftSternum({{0.65, false, 1}, {0.75, false, 1}, {0.85, false, 1}});
  ASSERT_EQ(f.size(), 3u);
  for (const ForceToLift& x : f) {
    // 21 mm of depression. The default cartilage is calibrated to in vivo forces: about 175 N in
    // adolescents, above 200 N in adults (Weber 2006); the full mesh gives 171-240 N (docs/planner.md).
    EXPECT_GT(x.force_n, 140.0);
    EXPECT_LT(x.force_n, 300.0);
  }
  // The force found, applied as a bar load and solved directly (Eigen's simplicial LDL^T of the
  // assembled stiffness, not the model's CHOLMOD factorisation nor its unit-force scaling), lifts the
  // sternum by the depression. Both solves are direct: they agree to round-off (1e-8 relative here;
  // a wrong force or a wrong lift per newton would be off by percents).
  const testing::DirectLift direct(*fem_);
  for (const ForceToLift& x : f) {
    const BarLoad found{x.position.position, x.position.position_in_mm, x.force_n};
    EXPECT_NEAR(direct.SternumLift(found), patient_->measured.depression_mm,
                1e-8 * patient_->measured.depression_mm)
        << found.Name();
  }
  // Pushing nearer the deepest point (the lower sternum) lifts it with less force.
  EXPECT_LT(f[2].force_n, f[1].force_n);
  EXPECT_LT(f[1].force_n, f[0].force_n);
  // The cartilage carries the load: the dissertation's four times softer cartilage (Table 1, 20 MPa)
  // needs less force, but more than a quarter (the ribs and sternum bend too): the full mesh needs 71 N.
  RibcageFemOptions table1;
  table1.materials.cartilage.youngs_modulus_mpa = kDissertationCartilageModulusMpa;
  const RibcageFem fem20(*patient_, table1);
  const ForceToLift g = fem20.ForceToLiftSternum({{0.75, false, 1}}).front();
  EXPECT_LT(g.force_n / f[1].force_n, 0.5);
  EXPECT_GT(g.force_n / f[1].force_n, 0.25);
}

// The push is spread with a smooth profile, so moving the bar by a fraction of a millimetre changes the
// lift by a little, smoothly: no jumps as rows of faces enter or leave the contact.
TEST_F(RibcageFemTest, TheLoadMovesContinuouslyWithTheBar) {
  const double length = patient_->measured.sternal_length_mm;
  std::vector<BarLoad> loads;
  for (int k = 0; k <= 10; ++k) loads.push_back({0.8 * length + 0.1 * k, true, 100.0});
  const std::vector<BarResult> r = fem_->Solve(loads);
  for (int k = 1; k < 10; ++k) {
    // Second differences are tiny compared with first differences: the lift is smooth in the position.
    const double first = r[k + 1].sternum_lift_mm - r[k - 1].sternum_lift_mm;
    const double second = r[k + 1].sternum_lift_mm - 2 * r[k].sternum_lift_mm + r[k - 1].sternum_lift_mm;
    EXPECT_LT(std::abs(second), 0.05 * std::abs(first) + 1e-9 * r[k].sternum_lift_mm) << k;
    EXPECT_LT(std::abs(first), 0.01 * r[k].sternum_lift_mm) << k;
  }
}

TEST_F(RibcageFemTest, BarOffTheSternumIsRefused) {
  EXPECT_THROW(fem_->Solve({{1.2, false, 100}}), Error);
  EXPECT_THROW(fem_->Solve({{0.8, false, -5}}), Error);
  const double length = patient_->measured.sternal_length_mm;
  // In millimetres from the notch, the same level as the fraction.
  EXPECT_NEAR(fem_->BarLevelZ({0.5 * length, true, 1}), fem_->BarLevelZ({0.5, false, 1}), 1e-12);
}

}  // namespace
}  // namespace pectus::planner
