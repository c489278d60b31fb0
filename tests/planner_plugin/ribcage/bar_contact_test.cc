// The bar as a shape: one-sided contact against the direct FE solve with the forces found, a bar behind
// the chest wall everywhere pushes nothing, a flat bar lifted into patient 57's depressed chest touches
// the sternum first and bears on it, and a deeper lift of a bent bar brings the cartilages in.
#include "planner_plugin/ribcage/bar_contact.h"

#include <gtest/gtest.h>

#include <cmath>

#include "planner_plugin/ribcage/build_generic_ribcage.h"
#include "shape/core/error.h"
#include "tests/planner_plugin/ribcage/coarse_patient.h"

namespace pectus::planner {
namespace {

// A flat bar's half length: across the front of the chest, between the anterior axillary lines (patient
// 57's ribcage is 250 mm wide).
constexpr double kHalfLength = 70.0;

class BarContactTest : public testing::CoarsePatient57Test {
 protected:
  // The candidates' largest y (the most posterior point of the chest wall's back at the level).
  static double MostPosteriorY(const BarContactResult& r) {
    double y = -1e9;
    for (std::int32_t node : r.nodes) y = std::max(y, patient_->mesh.nodes(node, 1));
    return y;
  }
};

// The gaps of the direct solve with the found forces: closed (within 0.01 mm) where a force acts, open
// everywhere else; forces only push.
void ExpectComplementarity(const PatientRibcage& patient, const BarContactResult& r, const BarShape& bar,
                           const Eigen::Vector3d& d) {
  ASSERT_TRUE(r.converged) << r.message;
  for (std::size_t i = 0; i < r.nodes.size(); ++i) {
    const auto k = static_cast<Eigen::Index>(i);
    // Small displacements: along the push direction, at the node's undeformed lateral position.
    const Eigen::Vector3d x0 = patient.mesh.nodes.row(r.nodes[i]).transpose();
    const Eigen::Vector3d p = x0 + r.displacement.row(r.nodes[i]).transpose();
    const double gap = p.dot(d) - (-bar.Y(x0.x()) + bar.lift_mm);
    EXPECT_GE(r.force_n[k], 0.0);
    EXPECT_GE(gap, -0.01) << "node " << r.nodes[i] << " goes through the bar";
    if (r.force_n[k] > 0.0) {
      EXPECT_NEAR(gap, 0.0, 0.01) << "node " << r.nodes[i] << " pushed but not touching";
    }
    EXPECT_NEAR(gap, r.gap_mm[k], 0.01)
        << "the compliance and the direct solve disagree at node " << r.nodes[i];
  }
}

TEST_F(BarContactTest, ABarBehindTheChestWallPushesNothing) {
  const double level = fem_->BarLevelZ({0.8, false, 1.0});
  const BarContactResult probe = SolveBarContact(*fem_, BarShape::Flat(level, 0.0, kHalfLength));
  const BarShape behind = BarShape::Flat(level, MostPosteriorY(probe) + 5.0, kHalfLength);
  const BarContactResult r = SolveBarContact(*fem_, behind);
  EXPECT_EQ(r.contacts, 0) << r.message;
  EXPECT_EQ(r.total_force_n, 0.0);
  EXPECT_EQ(r.displacement.cwiseAbs().maxCoeff(), 0.0);
  EXPECT_GT(r.gap0_mm.minCoeff(), 4.9);
}

// At the level of deepest depression (the CT's slice, where the surgeon places the bar) a flat bar lifted
// from behind touches the sternum first (patient 57's is a broad "saucer" depression of 21 mm: the chest
// wall rises from the sternum's depth on both sides), and only pushes: lifted by 1 mm it bears on the
// sternum alone, lifted by 3 mm still chiefly on it.
TEST_F(BarContactTest, AFlatBarTouchesTheSternumFirstAndOnlyPushes) {
  const double level = patient_->measured.slice_z_mm;
  const BarContactResult probe = SolveBarContact(*fem_, BarShape::Flat(level, 0.0, kHalfLength));
  // The first point the bar meets: the candidate farthest back.
  Eigen::Index first = 0;
  for (Eigen::Index i = 1; i < static_cast<Eigen::Index>(probe.nodes.size()); ++i) {
    if (patient_->mesh.nodes(probe.nodes[static_cast<std::size_t>(i)], 1) >
        patient_->mesh.nodes(probe.nodes[static_cast<std::size_t>(first)], 1))
      first = i;
  }
  EXPECT_EQ(probe.regions[static_cast<std::size_t>(first)], kSternumRegion)
      << "the flat bar meets node " << probe.nodes[static_cast<std::size_t>(first)]
      << " at x = " << patient_->mesh.nodes(probe.nodes[static_cast<std::size_t>(first)], 0) << " mm first";
  for (const double lift : {1.0, 3.0}) {
    BarShape bar = BarShape::Flat(level, MostPosteriorY(probe), kHalfLength);
    bar.lift_mm = lift;
    const BarContactResult r = SolveBarContact(*fem_, bar);
    ASSERT_GT(r.contacts, 0) << r.message;
    double on_sternum = 0.0;
    for (std::size_t i = 0; i < r.nodes.size(); ++i) {
      const double f = r.force_n[static_cast<Eigen::Index>(i)];
      if (r.regions[i] == kSternumRegion) on_sternum += f;
    }
    EXPECT_GE(on_sternum, (lift == 1.0 ? 0.999 : 0.5) * r.total_force_n) << r.message;
    ExpectComplementarity(*patient_, r, bar, fem_->options().push_direction);
    // The contact lifts the chest wall by the bar's lift where it touches, for a force of the order of
    // the force-to-lift figures per millimetre (patient 57: about 6 N/mm on this mesh).
    EXPECT_GT(r.total_force_n, 1.0 * lift);
    EXPECT_LT(r.total_force_n, 100.0 * lift);
  }
}

TEST_F(BarContactTest, ABentBarLiftedFarBringsTheCartilagesIn) {
  const double level = fem_->BarLevelZ({0.8, false, 1.0});
  const BarContactResult probe = SolveBarContact(*fem_, BarShape::Flat(level, 0.0, kHalfLength));
  // A bar bent forward at its ends (curved like the chest wall) and lifted by 25 mm.
  BarShape bar;
  bar.level_z_mm = level;
  const double back = MostPosteriorY(probe);
  for (double x = -90.0; x <= 90.0; x += 15.0) {
    bar.x_mm.push_back(x);
    bar.y_mm.push_back(back - 0.002 * x * x);
  }
  bar.lift_mm = 25.0;
  const BarContactResult r = SolveBarContact(*fem_, bar);
  int cartilage = 0;
  for (std::size_t i = 0; i < r.nodes.size(); ++i)
    cartilage += r.force_n[static_cast<Eigen::Index>(i)] > 0.0 && r.regions[i] == kCartilageRegion;
  EXPECT_GT(cartilage, 0) << r.message;
  ExpectComplementarity(*patient_, r, bar, fem_->options().push_direction);
}

TEST_F(BarContactTest, ABadBarIsRefused) {
  BarShape bar = BarShape::Flat(0.0, 0.0, kHalfLength);
  bar.x_mm = {0.0, 0.0};
  bar.y_mm = {1.0, 2.0};
  EXPECT_THROW(SolveBarContact(*fem_, bar), Error);
  EXPECT_THROW(SolveBarContact(*fem_, BarShape::Flat(1e4, 0.0, kHalfLength)), Error);  // far above the chest
}

}  // namespace
}  // namespace pectus::planner
