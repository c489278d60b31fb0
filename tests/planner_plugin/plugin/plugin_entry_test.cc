// The plugin's C boundary, loaded as any host would load it (dlopen): errors come back as status codes
// with messages, never as exceptions or aborts; C and C++ agree on the interface's layout; a planner
// made through the boundary measures like the CT.
#include <dlfcn.h>
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <string>

#include "planner_plugin/api/planner_api.h"
#include "planner_plugin/plugin/planner_session.h"
#include "tests/planner_plugin/plugin/plugin_fixture.h"
#include "tests/planner_plugin/ribcage/direct_lift.h"
#include "tests/support/require_shared_data.h"
#ifdef PECTUS_COUNT_ALLOCATIONS
#include "tests/support/allocation_counter.h"
#endif

extern "C" void pectus_planner_api_layout_from_c(size_t* out, int capacity);

namespace {

using PluginEntry = pectus::testing_support::PluginTest;

TEST_F(PluginEntry, ExportsOneVersionedTableThatCAndCppLayOutAlike) {
  ASSERT_NE(api_, nullptr);
  EXPECT_EQ(api_->version, PECTUS_PLANNER_INTERFACE_VERSION);
  EXPECT_EQ(api_->struct_size, sizeof(PectusPlannerInterface));
  EXPECT_NE(std::string(api_->description).find("pectus planner"), std::string::npos);
  constexpr int kItems = 33;
  size_t c[kItems] = {};
  pectus_planner_api_layout_from_c(c, kItems);
  const size_t cpp[kItems] = {sizeof(PectusPlannerStatus),
                              sizeof(PectusPlannerPatient),
                              sizeof(PectusPlannerOptions),
                              sizeof(PectusPlannerMeasurements),
                              sizeof(PectusPlannerMesh),
                              sizeof(PectusPlannerLandmark),
                              sizeof(PectusPlannerBar),
                              sizeof(PectusPlannerCaseResult),
                              sizeof(PectusPlannerForceToLift),
                              sizeof(PectusPlannerDatasetSummary),
                              sizeof(PectusPlannerBasisOptions),
                              sizeof(PectusPlannerBasisSummary),
                              offsetof(PectusPlannerInterface, deform),
                              sizeof(PectusPlannerInterface),
                              offsetof(PectusPlannerInterface, write_dataset),
                              offsetof(PectusPlannerPatient, ct_haller_index),
                              offsetof(PectusPlannerOptions, skin_columns),
                              PECTUS_PLANNER_INTERFACE_VERSION,
                              sizeof(PectusPlannerEmulatorOptions),
                              sizeof(PectusPlannerEmulatorFigures),
                              sizeof(PectusPlannerEmulatorPatient),
                              sizeof(PectusPlannerEmulatorEvaluation),
                              offsetof(PectusPlannerEmulatorFigures, worst_lift_patient),
                              offsetof(PectusPlannerInterface, evaluate_emulator),
                              offsetof(PectusPlannerInterface, basis_coefficients),
                              sizeof(PectusPlannerDeviceState),
                              sizeof(PectusPlannerDevice),
                              sizeof(PectusPlannerTrainerTick),
                              sizeof(PectusPlannerTunnel),
                              sizeof(PectusPlannerTrainerScore),
                              sizeof(PectusPlannerScopeView),
                              offsetof(PectusPlannerInterface, trainer_scope_view),
                              offsetof(PectusPlannerInterface, assemble_dataset)};
  for (int i = 0; i < kItems; ++i) EXPECT_EQ(c[i], cpp[i]) << "layout item " << i;
  // Nothing but the entry point is visible: not even the engine's functions (which this test binary
  // links itself, so the name below is the real one).
  EXPECT_EQ(dlsym(handle_, "_ZN6pectus7planner19BuildGenericRibcageERKNS0_21GenericRibcageOptionsE"),
            nullptr);
}

TEST_F(PluginEntry, DefaultMaterialsAreTableOneWithTheCartilageCalibratedToInVivoForces) {
  PectusPlannerOptions o{};
  api_->default_options(&o);
  EXPECT_EQ(o.sternum_youngs_modulus_mpa, 11500.0);  // dissertation Table 1
  EXPECT_EQ(o.sternum_poisson_ratio, 0.3);
  EXPECT_EQ(o.rib_youngs_modulus_mpa, 5000.0);
  EXPECT_EQ(o.rib_poisson_ratio, 0.3);
  EXPECT_EQ(o.cartilage_youngs_modulus_mpa, 80.0);  // calibrated (docs/planner.md); Table 1 says 20
  EXPECT_EQ(o.cartilage_poisson_ratio, 0.4);
}

TEST_F(PluginEntry, FailuresComeBackAsStatusesNamingWhatIsWrong) {
  PECTUS_REQUIRE_SHARED_FILE(pectus::testing_support::kPatientTable);
  PectusPlannerStatus status{};
  PectusPlannerPatient patient{};
  // A table that is not there: bad input, naming the file.
  EXPECT_EQ(api_->read_patient("/nonexistent/table.csv", "57", &patient, &status), PECTUS_PLANNER_BAD_INPUT);
  EXPECT_NE(std::string(status.message).find("/nonexistent/table.csv"), std::string::npos) << status.message;
  // A patient that is not in the table: a usage error listing what there is.
  EXPECT_EQ(api_->read_patient(pectus::testing_support::PatientTablePath().c_str(), "999", &patient, &status),
            PECTUS_PLANNER_USAGE);
  EXPECT_NE(std::string(status.message).find("999"), std::string::npos) << status.message;
  // NULL arguments.
  PectusPlanner* planner = nullptr;
  EXPECT_EQ(api_->create(nullptr, nullptr, &planner, &status), PECTUS_PLANNER_USAGE);
  EXPECT_EQ(api_->measurements(nullptr, nullptr, nullptr), PECTUS_PLANNER_USAGE);  // status may be NULL
  // A measurement out of range names the patient.
  ASSERT_EQ(api_->read_patient(pectus::testing_support::PatientTablePath().c_str(), "57", &patient, &status),
            PECTUS_PLANNER_OK)
      << status.message;
  PectusPlannerPatient deep = patient;
  deep.depression_mm = 90;
  EXPECT_EQ(api_->create(&deep, nullptr, &planner, &status), PECTUS_PLANNER_BAD_INPUT);
  EXPECT_EQ(planner, nullptr);
  EXPECT_NE(std::string(status.message).find("patient 57"), std::string::npos) << status.message;
  // An invalid material is a usage error naming the material.
  PectusPlannerOptions options = Coarse();
  options.cartilage_youngs_modulus_mpa = -1;
  EXPECT_EQ(api_->create(&patient, &options, &planner, &status), PECTUS_PLANNER_USAGE);
  EXPECT_NE(std::string(status.message).find("costal_cartilage"), std::string::npos) << status.message;
  // An id that is not NUL-terminated is caught, not read past.
  PectusPlannerPatient unterminated = patient;
  std::memset(unterminated.id, 'x', sizeof(unterminated.id));
  EXPECT_EQ(api_->create(&unterminated, nullptr, &planner, &status), PECTUS_PLANNER_BAD_INPUT);
  // A dataset that cannot be written is a failure, and nothing is left behind.
  EXPECT_EQ(api_->write_dataset("/nonexistent/table.csv", "/tmp/pectus_never.h5", nullptr, nullptr, nullptr,
                                nullptr, nullptr, &status),
            PECTUS_PLANNER_BAD_INPUT);
  EXPECT_FALSE(std::filesystem::exists("/tmp/pectus_never.h5"));
}

TEST_F(PluginEntry, APlannerThroughTheBoundaryMeasuresLikeTheCtAndSolves) {
  PECTUS_REQUIRE_SHARED_FILE(pectus::testing_support::kPatientTable);
  PectusPlannerStatus status{};
  PectusPlannerPatient patient{};
  ASSERT_EQ(api_->read_patient(pectus::testing_support::PatientTablePath().c_str(), "57", &patient, &status),
            PECTUS_PLANNER_OK)
      << status.message;
  EXPECT_DOUBLE_EQ(patient.ct_haller_index, 6.5);
  const PectusPlannerOptions options = Coarse();
  PectusPlanner* planner = nullptr;
  ASSERT_EQ(api_->create(&patient, &options, &planner, &status), PECTUS_PLANNER_OK) << status.message;
  PectusPlannerMeasurements m{};
  ASSERT_EQ(api_->measurements(planner, &m, &status), PECTUS_PLANNER_OK);
  // Patient 57: width 231, sternal length 168, depth 123, depression 21 mm (Appendix A).
  EXPECT_NEAR(m.width_mm, 231, 1.0);
  EXPECT_NEAR(m.depth_mm, 123, 1.0);
  EXPECT_NEAR(m.sternal_length_mm, 168, 1.0);
  EXPECT_NEAR(m.depression_mm, 21, 1.0);
  EXPECT_NEAR(m.haller_index, m.inner_width_mm / m.sternum_to_spine_mm, 1e-12);
  EXPECT_GT(m.haller_index, 4.0);
  // Landmarks: ask for the count first, then fill.
  std::int32_t count = 0;
  ASSERT_EQ(api_->landmarks(planner, 1, nullptr, 0, &count, &status), PECTUS_PLANNER_OK);
  ASSERT_EQ(count, 5);
  PectusPlannerLandmark marks[5];
  ASSERT_EQ(api_->landmarks(planner, 1, marks, 5, &count, &status), PECTUS_PLANNER_OK);
  EXPECT_STREQ(marks[0].label, "sternal_notch");
  // The reference landmarks (the chest without the deformity): the notch stays, the xiphoid comes
  // forward (-y) by more than the measured depression, less than twice it (the depression is measured
  // from the ribcage's highest point, which the skinning pulls down with the sternum).
  PectusPlannerLandmark reference[5];
  ASSERT_EQ(api_->landmarks(planner, PECTUS_PLANNER_REFERENCE_LANDMARKS, reference, 5, &count, &status),
            PECTUS_PLANNER_OK);
  EXPECT_NEAR(reference[0].position[1], marks[0].position[1], 1e-9);
  EXPECT_STREQ(reference[3].label, "xiphoid");
  const double forward = marks[3].position[1] - reference[3].position[1];
  EXPECT_GT(forward, 0.8 * m.depression_mm);
  EXPECT_LT(forward, 2.0 * m.depression_mm);
  EXPECT_EQ(api_->landmarks(planner, 3, reference, 5, &count, &status), PECTUS_PLANNER_USAGE);
  // Solve two cases; the lift is linear in the force.
  PectusPlannerMesh skin{};
  ASSERT_EQ(api_->skin_surface(planner, 0, &skin, &status), PECTUS_PLANNER_OK);
  EXPECT_EQ(skin.num_vertices, 24 * 32);
  const PectusPlannerBar bars[2] = {{0.8, 0, 100.0}, {0.8, 0, 300.0}};
  PectusPlannerCaseResult results[2];
  std::vector<double> positions(2 * 3 * static_cast<std::size_t>(skin.num_vertices));
  ASSERT_EQ(api_->solve(planner, bars, 2, nullptr, positions.data(), nullptr, results, &status),
            PECTUS_PLANNER_OK)
      << status.message;
  EXPECT_NEAR(results[1].sternum_lift_mm, 3.0 * results[0].sternum_lift_mm,
              1e-9 * results[1].sternum_lift_mm);
  // A bar off the sternum is refused with a message, not a crash.
  const PectusPlannerBar off = {1.3, 0, 100.0};
  EXPECT_EQ(api_->solve(planner, &off, 1, nullptr, nullptr, nullptr, nullptr, &status), PECTUS_PLANNER_USAGE);
  EXPECT_NE(std::string(status.message).find("off the sternum"), std::string::npos) << status.message;
  // Force to lift: the bar at the force found lifts the sternum by the depression in a direct solve of
  // its own (the same patient and options built in this process, its stiffness assembled and factorised
  // apart from the plugin's: round-off, 1e-8 relative; a wrong force would be off by percents).
  PectusPlannerForceToLift lift{};
  ASSERT_EQ(api_->force_to_lift(planner, bars, 1, &lift, &status), PECTUS_PLANNER_OK);
  const pectus::planner::PlannerSession here(pectus::planner::MeasurementsFrom(patient),
                                             pectus::planner::SettingsFrom(&options));
  const pectus::planner::testing::DirectLift direct(here.fem());
  EXPECT_NEAR(direct.SternumLift({bars[0].position, bars[0].position_in_mm != 0, lift.force_n}),
              m.depression_mm, 1e-8 * m.depression_mm);
  EXPECT_NEAR(lift.lift_per_newton_mm, results[0].sternum_lift_mm / 100.0, 1e-12);
  api_->destroy(planner);
  api_->destroy(nullptr);
}

// Version 2: the basis built through the boundary; the deform call gives what solve() gives (0.01 mm,
// the bound; the basis holds 0.001 mm) for bars between the dissertation's, with no allocation;
// the force for a lift agrees with force_to_lift(); failures come back as statuses, outputs untouched.
TEST_F(PluginEntry, TheDeformCallGivesTheSolvesAnswerInRealTime) {
  PECTUS_REQUIRE_SHARED_FILE(pectus::testing_support::kPatientTable);
  PectusPlannerStatus status{};
  PectusPlannerPatient patient{};
  ASSERT_EQ(api_->read_patient(pectus::testing_support::PatientTablePath().c_str(), "57", &patient, &status),
            PECTUS_PLANNER_OK)
      << status.message;
  const PectusPlannerOptions options = Coarse();
  PectusPlanner* planner = nullptr;
  ASSERT_EQ(api_->create(&patient, &options, &planner, &status), PECTUS_PLANNER_OK) << status.message;
  // No basis yet: a deformer is refused, saying what to do.
  PectusPlannerDeformer* deformer = nullptr;
  EXPECT_EQ(api_->create_deformer(planner, &deformer, &status), PECTUS_PLANNER_USAGE);
  EXPECT_NE(std::string(status.message).find("build_basis"), std::string::npos) << status.message;
  EXPECT_EQ(deformer, nullptr);
  PectusPlannerBasisSummary summary{};
  ASSERT_EQ(api_->build_basis(planner, nullptr, &summary, &status), PECTUS_PLANNER_OK) << status.message;
  PectusPlannerMesh bone{}, skin{};
  ASSERT_EQ(api_->bone_surface(planner, &bone, &status), PECTUS_PLANNER_OK);
  ASSERT_EQ(api_->skin_surface(planner, 0, &skin, &status), PECTUS_PLANNER_OK);
  EXPECT_EQ(summary.points, bone.num_vertices + skin.num_vertices + 5);
  EXPECT_GT(summary.rank, 0);
  EXPECT_LE(summary.truncation_bound_mm, 3e-3);  // the default tolerance
#ifdef PECTUS_COUNT_ALLOCATIONS
  const std::size_t before_create = pectus::testing_support::AllocationCount();
#endif
  ASSERT_EQ(api_->create_deformer(planner, &deformer, &status), PECTUS_PLANNER_OK) << status.message;
#ifdef PECTUS_COUNT_ALLOCATIONS
  // The counter sees the plugin's allocations: making the deformer sizes its buffers.
  EXPECT_GT(pectus::testing_support::AllocationCount(), before_create);
#endif

  const PectusPlannerBar bars[3] = {{0.62, 0, 80.0}, {0.77, 0, 450.0}, {131.0, 1, 1700.0}};
  const auto nb = static_cast<std::size_t>(bone.num_vertices),
             ns = static_cast<std::size_t>(skin.num_vertices);
  std::vector<double> bone_direct(3 * 3 * nb), skin_direct(3 * 3 * ns), marks_direct(3 * 5 * 3);
  PectusPlannerCaseResult results[3];
  ASSERT_EQ(api_->solve(planner, bars, 3, bone_direct.data(), skin_direct.data(), marks_direct.data(),
                        results, &status),
            PECTUS_PLANNER_OK)
      << status.message;
  std::vector<double> bone_fast(3 * nb), skin_fast(3 * ns), marks_fast(5 * 3);
  double worst = 0.0;
  for (int k = 0; k < 3; ++k) {
    double lift = 0.0;
#ifdef PECTUS_COUNT_ALLOCATIONS
    const std::size_t before = pectus::testing_support::AllocationCount();
#endif
    ASSERT_EQ(api_->deform(deformer, &bars[k], bone_fast.data(), skin_fast.data(), marks_fast.data(), &lift,
                           &status),
              PECTUS_PLANNER_OK)
        << status.message;
#ifdef PECTUS_COUNT_ALLOCATIONS
    EXPECT_EQ(pectus::testing_support::AllocationCount(), before) << "the deform call allocated";
#endif
    for (std::size_t i = 0; i < 3 * nb; ++i)
      worst = std::max(worst, std::abs(bone_fast[i] - bone_direct[3 * nb * k + i]));
    for (std::size_t i = 0; i < 3 * ns; ++i)
      worst = std::max(worst, std::abs(skin_fast[i] - skin_direct[3 * ns * k + i]));
    for (std::size_t i = 0; i < 15; ++i)
      worst = std::max(worst, std::abs(marks_fast[i] - marks_direct[15 * k + i]));
    EXPECT_NEAR(lift, results[k].sternum_lift_mm, 1e-3) << "bar " << k;
    // Something moved: the comparison is not of two undeformed chests.
    EXPECT_GT(results[k].max_displacement_mm, 1.0);
  }
  EXPECT_LT(worst, 0.01);
  std::printf("deform vs solve: largest difference %.2e mm over bone, skin and landmarks (rank %lld)\n",
              worst, static_cast<long long>(summary.rank));
  // The force for a lift: what force_to_lift() finds for the depression.
  PectusPlannerForceToLift to_lift{};
  ASSERT_EQ(api_->force_to_lift(planner, &bars[1], 1, &to_lift, &status), PECTUS_PLANNER_OK);
  PectusPlannerMeasurements m{};
  ASSERT_EQ(api_->measurements(planner, &m, &status), PECTUS_PLANNER_OK);
  double force = 0.0;
  ASSERT_EQ(api_->lift_force(deformer, &bars[1], m.depression_mm, &force, &status), PECTUS_PLANNER_OK);
  EXPECT_NEAR(force, to_lift.force_n, 1e-6 * to_lift.force_n);
  // Off the sternum, or a bad force: a status with the reason, the outputs untouched.
  const PectusPlannerBar off = {1.4, 0, 100.0}, bad = {0.8, 0, std::nan("")};
  std::vector<double> untouched(3 * ns, -7.0);
  EXPECT_EQ(api_->deform(deformer, &off, nullptr, untouched.data(), nullptr, nullptr, &status),
            PECTUS_PLANNER_USAGE);
  EXPECT_NE(std::string(status.message).find("off the sternum"), std::string::npos) << status.message;
  EXPECT_EQ(api_->deform(deformer, &bad, nullptr, untouched.data(), nullptr, nullptr, nullptr),
            PECTUS_PLANNER_USAGE);
  EXPECT_EQ(api_->lift_force(deformer, &off, 10.0, &force, &status), PECTUS_PLANNER_USAGE);
  EXPECT_TRUE(std::all_of(untouched.begin(), untouched.end(), [](double v) { return v == -7.0; }));
  EXPECT_EQ(api_->deform(nullptr, &bars[0], nullptr, nullptr, nullptr, nullptr, &status),
            PECTUS_PLANNER_USAGE);

  // The basis as a table (version 4): orthonormal modes, and coefficients that give deform()'s answer:
  // the difference between two forces at one position is their difference times U_r c.
  std::int64_t rows = 0, rank = 0;
  ASSERT_EQ(api_->basis_modes(planner, nullptr, 0, &rows, &rank, &status), PECTUS_PLANNER_OK)
      << status.message;
  EXPECT_EQ(rows, 3 * summary.points);
  EXPECT_EQ(rank, summary.rank);
  std::vector<float> modes(static_cast<std::size_t>(rows * rank));
  EXPECT_EQ(api_->basis_modes(planner, modes.data(), rows * rank - 1, &rows, &rank, &status),
            PECTUS_PLANNER_USAGE);
  ASSERT_EQ(api_->basis_modes(planner, modes.data(), rows * rank, &rows, &rank, &status), PECTUS_PLANNER_OK);
  const Eigen::Map<const Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>> U(
      modes.data(), rows, rank);
  const Eigen::MatrixXd gram = U.cast<double>().transpose() * U.cast<double>();
  // Orthonormal as the Gram route makes them (U = Y V / sigma: the weakest modes to about 1e-3).
  EXPECT_LT((gram - Eigen::MatrixXd::Identity(rank, rank)).cwiseAbs().maxCoeff(), 2e-3);
  Eigen::VectorXd c(rank);
  double lift_per_n = 0.0;
#ifdef PECTUS_COUNT_ALLOCATIONS
  const std::size_t before_coefficients = pectus::testing_support::AllocationCount();
#endif
  ASSERT_EQ(api_->basis_coefficients(deformer, &bars[2], c.data(), &lift_per_n, &status), PECTUS_PLANNER_OK)
      << status.message;
#ifdef PECTUS_COUNT_ALLOCATIONS
  EXPECT_EQ(pectus::testing_support::AllocationCount(), before_coefficients)
      << "basis_coefficients allocated";
#endif
  std::vector<double> all_high(3 * static_cast<std::size_t>(summary.points)), all_low(all_high.size());
  const PectusPlannerBar low = {bars[2].position, bars[2].position_in_mm, bars[2].force_n - 1000.0};
  double lift_high = 0.0;
  ASSERT_EQ(api_->deform(deformer, &bars[2], all_high.data(), all_high.data() + 3 * nb,
                         all_high.data() + 3 * (nb + ns), &lift_high, &status),
            PECTUS_PLANNER_OK);
  ASSERT_EQ(api_->deform(deformer, &low, all_low.data(), all_low.data() + 3 * nb,
                         all_low.data() + 3 * (nb + ns), nullptr, &status),
            PECTUS_PLANNER_OK);
  const Eigen::VectorXd table = 1000.0 * U.cast<double>() * c;
  double table_worst = 0.0;
  for (std::int64_t i = 0; i < rows; ++i)
    table_worst = std::max(table_worst, std::abs(all_high[i] - all_low[i] - table[i]));
  EXPECT_LT(table_worst, 1e-6) << "mm, 1000 N";
  EXPECT_GT(table.cwiseAbs().maxCoeff(), 1.0);  // the bar moves the chest: not two equal chests
  EXPECT_NEAR(lift_per_n * bars[2].force_n, lift_high, 1e-9);
  Eigen::VectorXd kept = Eigen::VectorXd::Constant(rank, -7.0);
  EXPECT_EQ(api_->basis_coefficients(deformer, &off, kept.data(), nullptr, &status), PECTUS_PLANNER_USAGE);
  EXPECT_NE(std::string(status.message).find("off the sternum"), std::string::npos) << status.message;
  EXPECT_TRUE((kept.array() == -7.0).all());
  api_->destroy_deformer(deformer);
  api_->destroy_deformer(nullptr);
  api_->destroy(planner);
}

}  // namespace
