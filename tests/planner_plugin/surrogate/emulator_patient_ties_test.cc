// A patient's ties from the boundary nodes to its skin and sternal lift: on patient 57's coarse ribcage
// (fitted, no FE) the skin through the ties equals SkinSurface::Deformed for a random nodal field, an
// anterior translation of 1 mm lifts the sternum by 1 mm; ThroughTies carries a prediction and its
// deviations by hand-checked numbers; the failure paths.
#include "planner_plugin/surrogate/emulator_patient_ties.h"

#include <gtest/gtest.h>

#include "planner_plugin/fem/tet_mesh.h"
#include "shape/core/error.h"
#include "shape/io/patient_table_io.h"
#include "tests/support/require_shared_data.h"

namespace pectus::planner {
namespace {

TEST(EmulatorPatientTiesTest, SkinAndLiftOfPatient57FollowTheBoundaryNodes) {
  PECTUS_REQUIRE_SHARED_FILE(testing_support::kPatientTable);
  GenericRibcageOptions o;  // the coarse test mesh (10 mm cells)
  o.sternum_cells_along = 28;
  o.rib_cell_length_mm = 10.0;
  const GenericRibcage generic = BuildGenericRibcage(o);
  const std::string table = testing_support::SharedPath(testing_support::kPatientTable);
  const PatientRibcage ribcage =
      MakePatientRibcage(generic, MeasurementsOf(FindPatient(ReadPatientTable(table), 57, table)));
  SkinSurfaceOptions skin_options;
  skin_options.rows = 16;
  skin_options.columns = 24;
  const SkinSurface skin = BuildSkinSurface(ribcage, skin_options);
  const std::vector<std::int32_t> boundary = ExtractBoundary(ribcage.mesh).nodes;
  const EmulatorPatientTies ties = MakeEmulatorPatientTies(ribcage, skin, boundary);
  ASSERT_EQ(ties.skin.rows(), 16 * 24);
  ASSERT_EQ(ties.skin.cols(), static_cast<Eigen::Index>(boundary.size()));
  // A random nodal field (zero off the boundary): the ties give SkinSurface::Deformed's displacement.
  Points3 u = Points3::Zero(ribcage.mesh.num_nodes(), 3);
  Eigen::VectorXd nodes = Eigen::VectorXd::Random(3 * static_cast<Eigen::Index>(boundary.size()));
  for (std::size_t b = 0; b < boundary.size(); ++b)
    u.row(boundary[b]) = nodes.segment<3>(3 * static_cast<Eigen::Index>(b));
  const Points3 expected = skin.Deformed(u) - skin.mesh.vertices.positions;
  ResponseEmulatorPrediction p;
  p.response = {nodes};
  p.response_sd = {Eigen::VectorXd::Ones(nodes.size())};
  const ResponseEmulatorPrediction through = ThroughTies(p, ties);
  EXPECT_LT((through.response[0] - Eigen::Map<const Eigen::VectorXd>(expected.data(), expected.size()))
                .cwiseAbs()
                .maxCoeff(),
            1e-12);
  // Rows sum to 1: a unit deviation at every node gives a unit deviation at every skin coordinate.
  EXPECT_LT((through.response_sd[0].array() - 1.0).abs().maxCoeff(), 1e-12);
  // Every node 1 mm anterior (-y): the sternum lifts 1 mm.
  for (Eigen::Index b = 0; b < static_cast<Eigen::Index>(boundary.size()); ++b)
    nodes.segment<3>(3 * b) = Eigen::Vector3d(0, -1, 0);
  p.response = {nodes};
  EXPECT_NEAR(ThroughTies(p, ties).lift_per_newton(0), 1.0, 1e-12);
  // A boundary set that misses the skin's nodes fails, naming the patient.
  try {
    MakeEmulatorPatientTies(ribcage, skin, {boundary.begin(), boundary.begin() + 10});
    ADD_FAILURE() << "no throw";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("patient 57"), std::string::npos) << e.what();
  }
}

TEST(EmulatorPatientTiesTest, ThroughTiesCarriesMeansAndDeviations) {
  // Two nodes; skin vertex 0 = 0.25 node 0 + 0.75 node 1, vertex 1 = node 1; lift = -(u_y of node 0).
  EmulatorPatientTies ties;
  ties.skin.resize(2, 2);
  ties.skin.insert(0, 0) = 0.25;
  ties.skin.insert(0, 1) = 0.75;
  ties.skin.insert(1, 1) = 1.0;
  ties.lift.resize(1, 6);
  ties.lift.insert(0, 1) = -1.0;
  ResponseEmulatorPrediction p;
  p.response = {(Eigen::VectorXd(6) << 1, -4, 2, 5, 0, -2).finished()};
  p.response_sd = {(Eigen::VectorXd(6) << 0.4, 0.8, 0.4, 0.2, 0.2, 0.2).finished()};
  const ResponseEmulatorPrediction out = ThroughTies(p, ties);
  const Eigen::VectorXd expected = (Eigen::VectorXd(6) << 4, -1, -1, 5, 0, -2).finished();
  EXPECT_LT((out.response[0] - expected).cwiseAbs().maxCoeff(), 1e-15);
  const Eigen::VectorXd sd = (Eigen::VectorXd(6) << 0.25, 0.35, 0.25, 0.2, 0.2, 0.2).finished();
  EXPECT_LT((out.response_sd[0] - sd).cwiseAbs().maxCoeff(), 1e-15);
  EXPECT_DOUBLE_EQ(out.lift_per_newton(0), 4.0);
  EXPECT_DOUBLE_EQ(out.lift_sd(0), 0.8);
  p.response = {Eigen::VectorXd::Zero(9)};
  EXPECT_THROW(ThroughTies(p, ties), Error);
}

}  // namespace
}  // namespace pectus::planner
