// Verification against CalculiX (ccx, C3D10): the identical mesh, materials, constraints and loads give
// the same displacements. Compiled only when ccx was found at configure time (PECTUS_CCX).
#include "planner_plugin/fem/calculix_io.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <random>

#include "planner_plugin/fem/hex_block.h"
#include "planner_plugin/fem/surface_load.h"
#include "planner_plugin/ribcage/ribcage_fem.h"
#include "shape/core/atomic_file.h"
#include "shape/core/error.h"
#include "tests/support/require_shared_data.h"

namespace pectus::planner {
namespace {

namespace fs = std::filesystem;

// Runs ccx on `mesh` with `load` in a fresh temporary folder; returns its displacements.
Points3 RunCalculix(const std::string& job, const TetMesh& mesh,
                    const std::vector<IsotropicMaterial>& materials,
                    const std::vector<std::int32_t>& prescribed, const LoadCase& load) {
  const fs::path dir = fs::temp_directory_path() / ("pectus_ccx_" + job + "_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  WriteCalculixInput(dir / (job + ".inp"), mesh, materials, prescribed, load);
  const std::string command =
      "cd '" + dir.string() + "' && OMP_NUM_THREADS=1 '" PECTUS_CCX "' -i " + job + " > ccx.log 2>&1";
  const int status = std::system(command.c_str());
  EXPECT_EQ(status, 0) << "ccx failed; see " << (dir / "ccx.log");
  Points3 u = ReadCalculixDisplacements(dir / (job + ".dat"), mesh.num_nodes());
  if (status == 0) fs::remove_all(dir);
  return u;
}

Eigen::Index mesh_nodes_of(const Points3& u) { return u.rows(); }

double RelativeDifference(const Points3& a, const Points3& b) {
  return (a - b).cwiseAbs().maxCoeff() / b.cwiseAbs().maxCoeff();
}

TEST(Calculix, ThreeMaterialBarMatchesCcxC3D10) {
  Points3 corners;
  Tet4Connectivity tets;
  MakeBoxTetrahedra(9, 2, 2, Eigen::Vector3d(90, 12, 10), &corners, &tets);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> jitter(-1.0, 1.0);
  for (Eigen::Index i = 0; i < corners.rows(); ++i)
    corners.row(i) += Eigen::RowVector3d(jitter(rng), jitter(rng), jitter(rng));
  // Three slabs along x: sternum-, cartilage- and rib-like stiffness.
  Eigen::VectorXi regions(tets.rows());
  for (Eigen::Index t = 0; t < tets.rows(); ++t) {
    const double x = (corners.row(tets(t, 0)) + corners.row(tets(t, 1)) + corners.row(tets(t, 2)) +
                      corners.row(tets(t, 3)))(0) /
                     4;
    regions(t) = x < 30 ? 0 : (x < 60 ? 1 : 2);
  }
  const TetMesh mesh = MakeQuadratic(corners, tets, regions);
  mesh.Validate("bar");
  const std::vector<IsotropicMaterial> materials = {
      {"sternum", 11500, 0.3}, {"cartilage", 20, 0.4}, {"rib", 5000, 0.3}};
  std::vector<std::int32_t> root;
  for (Eigen::Index i = 0; i < mesh.num_nodes(); ++i) {
    if (mesh.nodes(i, 0) < 2.0) root.push_back(static_cast<std::int32_t>(i));
  }
  const std::vector<std::int32_t> clamped = AllDofsOf(root);
  const MeshBoundary boundary = ExtractBoundary(mesh);
  std::vector<Eigen::Index> patch;
  for (Eigen::Index f = 0; f < boundary.faces.rows(); ++f) {
    if (mesh.nodes(boundary.faces(f, 0), 0) > 80 && mesh.nodes(boundary.faces(f, 1), 0) > 80 &&
        mesh.nodes(boundary.faces(f, 2), 0) > 80) {
      patch.push_back(f);
    }
  }
  Tri6Connectivity faces(static_cast<Eigen::Index>(patch.size()), 6);
  for (std::size_t k = 0; k < patch.size(); ++k)
    faces.row(static_cast<Eigen::Index>(k)) = boundary.faces.row(patch[k]);
  LoadCase load{"bar", Eigen::VectorXd::Zero(3 * mesh.num_nodes()), {}};
  AddForceOverPatch(mesh.nodes, faces, Eigen::Vector3d(3.0, -2.0, 5.0), &load.nodal_forces);

  LinearElasticSolver solver(mesh, materials, clamped);
  const Points3 ours = solver.Solve({load}).front();
  const Points3 theirs = RunCalculix("bar", mesh, materials, clamped, load);
  EXPECT_LT(RelativeDifference(ours, theirs), 1e-4) << "max |u| " << theirs.cwiseAbs().maxCoeff() << " mm";
  RecordProperty("relative_difference", std::to_string(RelativeDifference(ours, theirs)));
  RecordProperty("nodes", std::to_string(mesh_nodes_of(ours)));
}

// The patient-specific ribcage itself (a coarse mesh of patient 57: 10 mm cells), with the bar's push
// at 0.85 of the sternal length.
TEST(Calculix, PatientRibcageMatchesCcxC3D10) {
  PECTUS_REQUIRE_SHARED_FILE(testing_support::kPatientTable);
  GenericRibcageOptions o;
  o.sternum_cells_along = 28;
  o.rib_cell_length_mm = 10.0;
  const GenericRibcage generic = BuildGenericRibcage(o);
  const auto rows = ReadPatientTable(testing_support::PatientTablePath());
  const PatientRibcage patient =
      MakePatientRibcage(generic, MeasurementsOf(FindPatient(rows, 57, testing_support::PatientTablePath())));
  const RibcageFem fem(patient);
  const BarLoad bar{0.85, false, 100.0};
  const LoadCase load{"bar", fem.NodalForces(bar), {}};
  const Points3 ours = fem.solver().Solve({load}).front();
  const RibcageMaterials m;
  const Points3 theirs = RunCalculix("ribcage", patient.mesh, {m.sternum, m.rib, m.cartilage},
                                     fem.solver().partition().prescribed, load);
  EXPECT_LT(RelativeDifference(ours, theirs), 1e-4) << "max |u| " << theirs.cwiseAbs().maxCoeff() << " mm";
  RecordProperty("relative_difference", std::to_string(RelativeDifference(ours, theirs)));
  RecordProperty("nodes", std::to_string(mesh_nodes_of(ours)));
}

TEST(Calculix, ReadsOnlyWellFormedResults) {
  const fs::path path = fs::temp_directory_path() / ("pectus_ccx_bad_" + std::to_string(::getpid()) + ".dat");
  WriteFileAtomically(path,
                      "\n displacements (vx,vy,vz) for set NALL and time  0.1000000E+01\n\n"
                      "         1  1.0E+00  2.0E+00  3.0E+00\n");
  EXPECT_THROW(ReadCalculixDisplacements(path, 2), Error);  // one node of two
  const Points3 u = ReadCalculixDisplacements(path, 1);
  EXPECT_EQ(u(0, 2), 3.0);
  // A node listed twice (and so another never) was read as complete with NaN for the missing node.
  WriteFileAtomically(path,
                      "\n displacements (vx,vy,vz) for set NALL and time  0.1000000E+01\n\n"
                      "         1  1.0E+00  2.0E+00  3.0E+00\n         1  1.0E+00  2.0E+00  3.0E+00\n");
  try {
    ReadCalculixDisplacements(path, 2);
    ADD_FAILURE() << "no error for a node listed twice";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::kBadInput);
    EXPECT_EQ(e.line(), 5);
    EXPECT_NE(std::string(e.what()).find("node 1 listed twice (first on line 4)"), std::string::npos)
        << e.what();
  }
  fs::remove(path);
}

}  // namespace
}  // namespace pectus::planner
