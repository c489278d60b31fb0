// The compressed response basis against the direct FE solve: every node's displacement for the
// dissertation's 24 load cases and random (position, force) pairs, the skin through its ties, the sternal
// lift per newton, a bar off the sternum.
#include "planner_plugin/ribcage/bar_response_basis.h"

#include <gtest/gtest.h>

#include <random>

#include "planner_plugin/ribcage/build_skin_surface.h"
#include "shape/core/error.h"
#include "tests/planner_plugin/ribcage/coarse_patient.h"

namespace pectus::planner {
namespace {

// Patient 57 on the coarse test mesh (10 mm cells).
class BarResponseBasisTest : public testing::CoarsePatient57Test {
 protected:
  static void TearDownTestSuite() {
    delete basis_;
    delete skin_;
    basis_ = nullptr, skin_ = nullptr;
    CoarsePatient57Test::TearDownTestSuite();
  }
  // The basis, built on first use (each test runs in its own process): output points every node, then
  // every skin vertex through its ties.
  static const BarResponseBasis& Basis() {
    if (basis_ == nullptr) {
      skin_ = new SkinSurface(BuildSkinSurface(*patient_));
      std::vector<NodeTies> points;
      for (std::int32_t i = 0; i < patient_->mesh.num_nodes(); ++i) points.push_back({{i, 1.0}});
      points.insert(points.end(), skin_->ties.begin(), skin_->ties.end());
      basis_ = new BarResponseBasis(*fem_, points);
    }
    return *basis_;
  }
  static inline SkinSurface* skin_ = nullptr;
  static inline BarResponseBasis* basis_ = nullptr;
};

TEST_F(BarResponseBasisTest, EqualsTheDirectSolveForTheDissertationCasesAndRandomBars) {
  std::vector<BarLoad> loads = DissertationLoadCases();
  std::mt19937 rng(14);
  std::uniform_real_distribution<double> position(0.3, 0.97), force(10.0, 2000.0);
  for (int k = 0; k < 40; ++k) loads.push_back({position(rng), false, force(rng)});
  loads.push_back({120.0, true, 700.0});  // in mm from the notch
  const std::vector<BarResult> direct = fem_->Solve(loads);
  const BarResponseBasis* basis_ = &Basis();
  BarResponseWorkspace ws = basis_->MakeWorkspace();
  const Eigen::Index nodes = patient_->mesh.num_nodes(), skin = skin_->mesh.num_vertices();
  ASSERT_EQ(basis_->num_points(), nodes + skin);
  Points3 u(nodes + skin, 3);
  double worst = 0.0, worst_skin = 0.0, skin_moves = 0.0;
  for (std::size_t k = 0; k < loads.size(); ++k) {
    ASSERT_TRUE(basis_->Evaluate(basis_->LevelZ(loads[k]), loads[k].force_n, &ws, u.data()))
        << loads[k].Name();
    // The compression is stated at 0.001 mm up to 2000 N: every node within it of the direct solve.
    const double e = (u.topRows(nodes) - direct[k].displacement).rowwise().norm().maxCoeff();
    worst = std::max(worst, e);
    EXPECT_LT(e, 1e-3) << loads[k].Name() << ": largest displacement " << direct[k].max_displacement_mm
                       << " mm";
    // The skin through its ties, as SkinSurface::Deformed moves it.
    const Points3 skin_moved = skin_->Deformed(direct[k].displacement) - skin_->mesh.vertices.positions;
    const double es = (u.bottomRows(skin) - skin_moved).rowwise().norm().maxCoeff();
    worst_skin = std::max(worst_skin, es);
    skin_moves = std::max(skin_moves, skin_moved.rowwise().norm().maxCoeff());
    EXPECT_LT(es, 1e-3) << loads[k].Name();
    // The sternal lift and the force for a wanted lift, from the exact lift row.
    const double lift = basis_->LiftPerNewton(basis_->LevelZ(loads[k])) * loads[k].force_n;
    EXPECT_NEAR(lift, direct[k].sternum_lift_mm, 1e-9 * std::abs(direct[k].sternum_lift_mm))
        << loads[k].Name();
  }
  std::printf(
      "basis: %lld contact nodes, rank %lld, %.1f MB; largest difference from the direct solve %.2e mm "
      "(nodes), %.2e mm (skin); singular values %.3g ... %.3g mm/N\n",
      static_cast<long long>(basis_->num_contact_nodes()), static_cast<long long>(basis_->rank()),
      static_cast<double>(basis_->bytes()) / 1e6, worst, worst_skin, basis_->singular_values()[0],
      basis_->singular_values()[basis_->singular_values().size() - 1]);
  // Compressed, and the stated bound holds.
  EXPECT_LT(basis_->rank(), basis_->num_contact_nodes() / 2);
  EXPECT_LE(basis_->truncation_bound_mm_per_n() * 2000.0, BarResponseBasisOptions{}.tolerance_mm);
  EXPECT_GT(skin_moves, 1.0);  // the skin really moves (mm)
}

TEST_F(BarResponseBasisTest, ABarOffTheSternumIsReportedAndWritesNothing) {
  // A small basis: the ten first nodes.
  std::vector<NodeTies> points;
  for (std::int32_t i = 0; i < 10; ++i) points.push_back({{i, 1.0}});
  const BarResponseBasis small(*fem_, points);
  const BarResponseBasis* basis_ = &small;
  BarResponseWorkspace ws = basis_->MakeWorkspace();
  std::vector<double> out(static_cast<std::size_t>(3 * basis_->num_points()), 7.0);
  const double above_the_notch = basis_->LevelZ({-40.0, true, 1.0});
  EXPECT_FALSE(basis_->Evaluate(above_the_notch, 100.0, &ws, out.data()));
  EXPECT_EQ(out.front(), 7.0);
  EXPECT_EQ(basis_->LiftPerNewton(above_the_notch), 0.0);
  // Usable again afterwards.
  EXPECT_TRUE(basis_->Evaluate(basis_->LevelZ({0.7, false, 1.0}), 100.0, &ws, out.data()));
  // Rows 5 to 22 alone (not on the 8-row panels' edges): the same values there, nothing else written.
  std::vector<double> part(out.size(), 7.0);
  EXPECT_TRUE(basis_->Evaluate(basis_->LevelZ({0.7, false, 1.0}), 100.0, &ws, part.data(), 5, 23));
  for (std::size_t i = 0; i < part.size(); ++i) {
    if (i >= 5 && i < 23)
      EXPECT_EQ(part[i], out[i]) << i;
    else
      EXPECT_EQ(part[i], 7.0) << i;
  }
}

TEST_F(BarResponseBasisTest, BadTiesAndOptionsAreRefused) {
  EXPECT_THROW(BarResponseBasis(*fem_, {{{-1, 1.0}}}), Error);
  EXPECT_THROW(BarResponseBasis(*fem_, {{{static_cast<std::int32_t>(patient_->mesh.num_nodes()), 1.0}}}),
               Error);
  BarResponseBasisOptions o;
  o.tolerance_mm = 0.0;
  EXPECT_THROW(BarResponseBasis(*fem_, {{{0, 1.0}}}, o), Error);
}

}  // namespace
}  // namespace pectus::planner

namespace pectus::planner {
namespace {

// Stored and made again (as the FE dataset keeps it): the same evaluations bit for bit, the same lift;
// inconsistent arrays refused with a message naming the source.
TEST_F(BarResponseBasisTest, StoredAndMadeAgainItEvaluatesTheSame) {
  const BarResponseBasis& basis = Basis();
  const BarResponseBasis again(basis.ToStored(), "test");
  EXPECT_EQ(again.rank(), basis.rank());
  EXPECT_EQ(again.num_points(), basis.num_points());
  EXPECT_EQ(again.num_contact_nodes(), basis.num_contact_nodes());
  EXPECT_EQ(again.bytes(), basis.bytes());
  BarResponseWorkspace a = basis.MakeWorkspace(), b = again.MakeWorkspace();
  std::vector<double> ua(3 * static_cast<std::size_t>(basis.num_points())), ub(ua.size());
  for (double position : {0.55, 0.7, 0.83, 0.9}) {
    const double level = basis.LevelZ({position, false, 1.0});
    EXPECT_EQ(again.LevelZ({position, false, 1.0}), level);
    ASSERT_TRUE(basis.Evaluate(level, 300.0, &a, ua.data()));
    ASSERT_TRUE(again.Evaluate(level, 300.0, &b, ub.data()));
    EXPECT_EQ(ua, ub) << "position " << position;
    EXPECT_EQ(again.LiftPerNewton(level), basis.LiftPerNewton(level));
  }
  // Broken arrays.
  auto refused = [](BarResponseBasis::Stored s, const std::string& expected) {
    try {
      BarResponseBasis bad(std::move(s), "bases.h5");
      ADD_FAILURE() << "accepted: " << expected;
    } catch (const Error& e) {
      EXPECT_EQ(e.kind(), ErrorKind::kBadInput);
      EXPECT_NE(std::string(e.what()).find("bases.h5"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(expected), std::string::npos) << e.what();
    }
  };
  BarResponseBasis::Stored s = basis.ToStored();
  s.num_points += 1;
  refused(s, "rows");
  s = basis.ToStored();
  s.quadrature_contact(3, 2) = static_cast<int>(s.contact_nodes.size());
  refused(s, "beyond");
  s = basis.ToStored();
  std::swap(s.quadrature_z[0], s.quadrature_z[s.quadrature_z.size() - 1]);
  refused(s, "ascending");
  s = basis.ToStored();
  s.mixing(0, 0) = std::nan("");
  refused(s, "non-finite");
  s = basis.ToStored();
  s.lift.resize(3);
  refused(s, "mixing");
}

}  // namespace
}  // namespace pectus::planner
