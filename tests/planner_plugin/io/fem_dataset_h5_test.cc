// The FE dataset (dissertation §4.1.2): every patient x 24 load cases, read back with HDF5: the layout
// docs/planner.md documents, the load cases in order, and displacements that are the FE solutions.
#include "planner_plugin/io/fem_dataset_h5.h"

#include <gtest/gtest.h>
#include <hdf5.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <utility>
#include <vector>

#include "planner_plugin/plugin/planner_session.h"
#include "planner_plugin/plugin/run_fem_dataset.h"
#include "shape/core/error.h"
#include "shape/io/patient_table_io.h"
#include "tests/support/bad_input.h"

namespace pectus::planner {
namespace {
namespace fs = std::filesystem;
using testing_support::BadInputMessage;

std::vector<hsize_t> Dims(hid_t file, const char* name) {
  const hid_t set = H5Dopen2(file, name, H5P_DEFAULT);
  EXPECT_GE(set, 0) << name;
  const hid_t space = H5Dget_space(set);
  std::vector<hsize_t> dims(static_cast<std::size_t>(H5Sget_simple_extent_ndims(space)));
  H5Sget_simple_extent_dims(space, dims.data(), nullptr);
  H5Sclose(space);
  H5Dclose(set);
  return dims;
}

template <typename T>
std::vector<T> Read(hid_t file, const char* name, hid_t type, std::size_t count) {
  std::vector<T> values(count);
  const hid_t set = H5Dopen2(file, name, H5P_DEFAULT);
  EXPECT_GE(H5Dread(set, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, values.data()), 0) << name;
  H5Dclose(set);
  return values;
}

TEST(FemDataset, EveryPatientTimesTwentyFourLoadCasesReadsBack) {
  const fs::path dir = fs::temp_directory_path() / ("pectus_fem_dataset_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  {
    std::ofstream table(dir / "two.csv");
    table << "patient,haller_index,width_mm,sternal_length_mm,depth_mm,depression_mm\n"
             "57,6.5,231,168,123,21\n"
             "3,6.3,280,165,151,40\n";
  }
  PlannerSettings settings = SettingsFrom(nullptr);
  settings.generic.rib_cell_length_mm = 10;  // a coarse mesh of the whole ribcage (all 10 rib pairs)
  settings.generic.sternum_cells_along = 28;
  int calls = 0;
  const FemDatasetSummary s =
      RunFemDataset(dir / "two.csv", dir / "fem.h5", settings, [&](std::int64_t done, std::int64_t total) {
        ++calls;
        EXPECT_EQ(done, calls);
        EXPECT_EQ(total, 2);
      });
  EXPECT_EQ(calls, 2);
  EXPECT_EQ(s.patients, 2);
  EXPECT_EQ(s.results, 48);
  ASSERT_TRUE(fs::exists(dir / "fem.h5"));
  EXPECT_FALSE(fs::exists(dir / ".fem.h5.partial"));

  const hid_t file = H5Fopen((dir / "fem.h5").c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  ASSERT_GE(file, 0);
  const auto forces = Read<double>(file, "/load_cases/force_n", H5T_NATIVE_DOUBLE, 24);
  const auto positions = Read<double>(file, "/load_cases/position", H5T_NATIVE_DOUBLE, 24);
  const double expected[8] = {50, 70, 100, 200, 400, 800, 1500, 2000};
  for (int k = 0; k < 24; ++k) {
    EXPECT_EQ(forces[k], expected[k % 8]);
    EXPECT_EQ(positions[k], (k < 8 ? 0.65 : k < 16 ? 0.75 : 0.85));
  }
  const auto n = static_cast<hsize_t>(s.surface_nodes);
  EXPECT_EQ(Dims(file, "/patients/57/nodes"), (std::vector<hsize_t>{n, 3}));
  EXPECT_EQ(Dims(file, "/patients/3/displacements"), (std::vector<hsize_t>{24, n, 3}));
  EXPECT_EQ(Dims(file, "/topology/faces")[1], 3u);
  // The model is linear: at one position the 2000 N case is 40 times the 50 N case (float32 storage).
  const auto u = Read<float>(file, "/patients/57/displacements", H5T_NATIVE_FLOAT, 24 * n * 3);
  const auto lift = Read<double>(file, "/patients/57/sternum_lift", H5T_NATIVE_DOUBLE, 24);
  double worst = 0, largest = 0;
  for (std::size_t i = 0; i < n * 3; ++i) {
    worst = std::max(worst, std::abs(static_cast<double>(u[23 * n * 3 + i]) - 40.0 * u[16 * n * 3 + i]));
    largest = std::max(largest, std::abs(static_cast<double>(u[23 * n * 3 + i])));
  }
  EXPECT_LT(worst, 1e-5 * largest);
  EXPECT_NEAR(lift[23], 40.0 * lift[16], 1e-9 * lift[23]);
  EXPECT_GT(lift[23], 0.0);
  const hsize_t num_faces = Dims(file, "/topology/faces")[0];
  H5Fclose(file);

  // pectus's own reader gives the same numbers as the HDF5 calls above.
  const FemDataset d = ReadFemDataset(dir / "fem.h5");
  ASSERT_EQ(d.position.size(), 24);
  ASSERT_EQ(d.patients.size(), 2u);
  EXPECT_EQ(d.position[9], positions[9]);
  EXPECT_EQ(d.force_n[9], forces[9]);
  EXPECT_EQ(d.faces.rows(), static_cast<Eigen::Index>(num_faces));
  const FemDataset::Patient& p57 = d.patients[0].id == "57" ? d.patients[0] : d.patients[1];
  EXPECT_EQ(p57.id, "57");
  ASSERT_EQ(p57.displacements_mm.size(), 24u);
  EXPECT_EQ(p57.nodes_mm.rows(), static_cast<Eigen::Index>(n));
  EXPECT_EQ(p57.displacements_mm[23](5, 1), static_cast<double>(u[23 * n * 3 + 5 * 3 + 1]));
  EXPECT_EQ(p57.sternum_lift_mm[23], lift[23]);
  fs::remove_all(dir);
}

// With bases: each patient's exact response basis stored and read back array for array; a planner of the
// same patient and options takes it instead of building one and deforms as the direct solve does; a
// planner of other materials, or a patient the file lacks, is refused naming the file.
TEST(FemDataset, TheResponseBasisIsStoredAndTakenBackByTheSamePlannerOnly) {
  const fs::path dir = fs::temp_directory_path() / ("pectus_fem_bases_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  {
    std::ofstream table(dir / "one.csv");
    table << "patient,haller_index,width_mm,sternal_length_mm,depth_mm,depression_mm\n"
             "57,6.5,231,168,123,21\n";
  }
  PlannerSettings settings = SettingsFrom(nullptr);
  settings.generic.rib_cell_length_mm = 10;
  settings.generic.sternum_cells_along = 28;
  settings.skin.rows = 16;
  settings.skin.columns = 24;
  const BarResponseBasisOptions basis_options;
  const FemDatasetSummary s =
      RunFemDataset(dir / "one.csv", dir / "fem.h5", settings, nullptr, &basis_options);
  EXPECT_GT(s.timings_s.Seconds("response_basis"), 0.0);
  const FemDataset d = ReadFemDataset(dir / "fem.h5");
  ASSERT_EQ(d.patients.size(), 1u);
  ASSERT_TRUE(d.patients[0].basis.has_value());
  const StoredResponseBasis stored = ReadStoredResponseBasis(dir / "fem.h5", "57");
  EXPECT_EQ(stored.skin_vertices, 16 * 24);
  EXPECT_EQ(stored.skin_landmarks, 5);
  EXPECT_EQ(stored.arrays.modes, d.patients[0].basis->arrays.modes);

  // The same planner takes it: what it gives equals the basis it builds itself, bit for bit, and the
  // direct solve within 0.001 mm.
  const PatientMeasurements patient = MeasurementsOf(ReadPatientTable(dir / "one.csv").front());
  PlannerSession session(patient, settings);
  session.LoadBasis(stored, (dir / "fem.h5").string());
  EXPECT_EQ(session.basis()->ToStored().modes, stored.arrays.modes);
  EXPECT_EQ(session.basis()->ToStored().mixing, stored.arrays.mixing);
  SessionDeformer deformer(session);
  const BarLoad bar{0.8, false, 400.0};
  std::vector<double> bone(3 * static_cast<std::size_t>(session.num_bone_vertices()));
  const char* why = "";
  ASSERT_TRUE(deformer.Deform(bar, bone.data(), nullptr, nullptr, nullptr, &why)) << why;
  const BarResult direct = session.fem().Solve({bar}).front();
  const BoneSurface surface = MakeBoneSurface(session.ribcage());
  double worst = 0.0;
  for (Eigen::Index i = 0; i < surface.vertices.rows(); ++i) {
    for (int c = 0; c < 3; ++c) {
      worst = std::max(worst, std::abs(bone[3 * i + c] - surface.vertices(i, c) -
                                       direct.displacement(surface.mesh_nodes[i], c)));
    }
  }
  EXPECT_LT(worst, 1e-3);

  // Other materials: refused.
  PlannerSettings softer = settings;
  softer.fem.materials.cartilage.youngs_modulus_mpa = 20.0;
  PlannerSession other(patient, softer);
  EXPECT_NE(
      BadInputMessage([&] { other.LoadBasis(stored, (dir / "fem.h5").string()); }, (dir / "fem.h5").string())
          .find("other materials"),
      std::string::npos);
  // A patient the file lacks.
  EXPECT_NE(BadInputMessage([&] { ReadStoredResponseBasis(dir / "fem.h5", "12"); }, (dir / "fem.h5").string())
                .find("has no patient '12'"),
            std::string::npos);
  fs::remove_all(dir);
}

TEST(FemDataset, MalformedFilesAreBadInputNamingTheDataset) {
  const fs::path path = fs::temp_directory_path() / ("pectus_fem_bad_" + std::to_string(::getpid()) + ".h5");
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  // Two load-case positions but three forces.
  const hid_t file = H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
  ASSERT_GE(file, 0);
  const hid_t links = H5Pcreate(H5P_LINK_CREATE);
  H5Pset_create_intermediate_group(links, 1);
  for (const auto& [name, size] : {std::pair{"load_cases/position", 2}, std::pair{"load_cases/force_n", 3}}) {
    const hsize_t dims = static_cast<hsize_t>(size);
    const std::vector<double> values(dims, 0.5);
    const hid_t space = H5Screate_simple(1, &dims, nullptr);
    const hid_t set = H5Dcreate2(file, name, H5T_NATIVE_DOUBLE, space, links, H5P_DEFAULT, H5P_DEFAULT);
    H5Dwrite(set, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, values.data());
    H5Dclose(set);
    H5Sclose(space);
  }
  H5Pclose(links);
  H5Fclose(file);
  std::string what = BadInputMessage([&] { ReadFemDataset(path); }, path.string());
  EXPECT_NE(what.find("/load_cases/force_n has extent 3 in dimension 1, expected 2"), std::string::npos)
      << what;
  std::ifstream in(path, std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  what = BadInputMessage([&] { ParseFemDataset(bytes, "memory.h5"); }, "memory.h5");
  EXPECT_NE(what.find("/load_cases/force_n has extent 3"), std::string::npos) << what;
  BadInputMessage([&] { ParseFemDataset("hello", "memory.h5"); }, "memory.h5");
  BadInputMessage([&] { ReadFemDataset(path.string() + ".missing"); }, path.string() + ".missing");
  fs::remove(path);
}

}  // namespace
}  // namespace pectus::planner

namespace pectus::planner {
namespace {

std::string Bytes(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

// The dataset by parts (a task farm's way, docs/cluster.md): parts made in any order and assembled in
// table order are RunFemDataset's bytes, and assembling again gives them again (no times in the file); a
// part made with other options, or the same patient twice, is refused naming the part.
TEST(FemDataset, PartsAssembledInTableOrderAreTheWholeRunsBytes) {
  const fs::path dir = fs::temp_directory_path() / ("pectus_fem_parts_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  std::ofstream(dir / "two.csv") << "patient,haller_index,width_mm,sternal_length_mm,depth_mm,depression_mm\n"
                                    "57,6.5,231,168,123,21\n"
                                    "3,6.3,280,165,151,40\n";
  PlannerSettings settings = SettingsFrom(nullptr);  // the coarsest mesh and skin: the test is about bytes
  settings.generic.rib_cell_length_mm = 20;
  settings.skin.rows = 8;
  settings.skin.columns = 12;
  RunFemDataset(dir / "two.csv", dir / "whole.h5", settings, nullptr);
  const auto rows = ReadPatientTable(dir / "two.csv");
  const GenericRibcage generic = BuildGenericRibcage(settings.generic);
  RunFemDatasetPart(generic, rows[1], dir / "b.h5", settings);  // the second patient first
  RunFemDatasetPart(generic, rows[0], dir / "a.h5", settings);
  const FemDatasetAssembly a = AssembleFemDataset({dir / "a.h5", dir / "b.h5"}, dir / "farm.h5");
  EXPECT_EQ(a.patients, (std::vector<std::string>{"57", "3"}));
  EXPECT_EQ(a.load_cases, 24);
  EXPECT_GT(a.surface_nodes, 100);
  const std::string whole = Bytes(dir / "whole.h5");
  ASSERT_GT(whole.size(), 10000u);
  EXPECT_TRUE(Bytes(dir / "farm.h5") == whole) << "the parts assembled differ from the whole run's dataset";
  AssembleFemDataset({dir / "a.h5", dir / "b.h5"}, dir / "again.h5");
  EXPECT_TRUE(Bytes(dir / "again.h5") == whole) << "a second assembly differs";
  EXPECT_EQ(ReadFemDataset(dir / "farm.h5").patients.size(), 2u);

  PlannerSettings other = settings;
  other.generic.rib_cell_length_mm = 16;
  RunFemDatasetPart(BuildGenericRibcage(other.generic), rows[1], dir / "other.h5", other);
  const std::string refused = BadInputMessage(
      [&] {
        AssembleFemDataset({dir / "a.h5", dir / "other.h5"}, dir / "x.h5");
      },
      (dir / "other.h5").string());
  EXPECT_NE(refused.find("other options"), std::string::npos) << refused;
  const std::string twice = BadInputMessage(
      [&] {
        AssembleFemDataset({dir / "a.h5", dir / "a.h5"}, dir / "x.h5");
      },
      (dir / "a.h5").string());
  EXPECT_NE(twice.find("another part holds too"), std::string::npos) << twice;
  EXPECT_FALSE(fs::exists(dir / "x.h5"));
  if (!HasFailure()) fs::remove_all(dir);
}

}  // namespace
}  // namespace pectus::planner
