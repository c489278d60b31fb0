// The leave-one-patient-out evaluation of the response emulator, on training sets with a known answer:
// the error figures of hand-computed cases; node responses the same in every patient but skin ties of the
// patient's own (the emulator, carried through the left-out patient's ties, is exact; the baselines, which
// average other patients' skins, are not); a smooth low-rank family of node responses (the emulator within
// 1 %, far better than the baselines); the nearest patient found; bad sets and options refused.
#include "planner_plugin/surrogate/emulator_evaluation.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "shape/core/error.h"

namespace pectus::planner {
namespace {

TEST(EmulatorErrorsTest, FiguresOfHandComputedCases) {
  EmulatorErrors errors;
  // Two vertices; errors 0.3 and 0.4 mm; FE norm sqrt(2); predicted deviation 0.18 (2 sigma 0.36).
  Eigen::VectorXd fe(6), predicted(6);
  fe << 1, 0, 0, 0, 1, 0;
  predicted << 1.3, 0, 0, 0, 1.4, 0;
  errors.Add(predicted, fe, Eigen::VectorXd::Constant(6, 0.18), 10.5, 10.0, 3);
  // A second case, lift above 40 mm: in the relative L2 and all-case lift error only.
  errors.Add(2.0 * fe, fe, {}, 52.0, 50.0, 7);
  const EmulatorErrors::Summary s = errors.Summarise();
  EXPECT_EQ(s.cases, 2);
  EXPECT_EQ(s.small_lift_cases, 1);
  EXPECT_NEAR(s.skin_rms.mean, std::sqrt(0.125), 1e-12);
  EXPECT_NEAR(s.skin_p95.mean, 0.3 + 0.95 * 0.1, 1e-12);  // linear between the two vertices' errors
  EXPECT_NEAR(s.relative_l2.mean, 0.5 * (0.5 / std::sqrt(2.0) + 1.0), 1e-12);
  EXPECT_NEAR(s.relative_l2.max, 1.0, 1e-12);
  EXPECT_NEAR(s.relative_l2.within, 0.0, 0.0);
  EXPECT_NEAR(s.small_lift_error.mean, 0.5, 1e-12);
  EXPECT_NEAR(s.lift_error.max, 2.0, 1e-12);
  EXPECT_NEAR(s.coverage_2sd, 5.0 / 6.0, 1e-12);  // 0.4 > 0.36; the other five coordinates are within
  EXPECT_EQ(s.worst_relative_l2_patient, 7);
  EXPECT_EQ(s.worst_lift_patient, 7);
  EXPECT_EQ(s.worst_skin_rms_patient, 3);
  EXPECT_THROW(errors.Add(fe, Eigen::VectorXd(3), {}, 0, 0, 0), Error);
}

// n patients, q = 2 positions, 5 boundary nodes, a 2 x 2 skin grid. Patient i's inputs: the fitted map
// (scale x, y, z, depression). Node responses per newton (3 x 5 coordinates): `smooth` a smooth function of
// the inputs of rank 3, otherwise the same for everyone. Each skin vertex is a patient's own blend of two
// nodes; the sternal lift is node 0's y.
EmulatorTrainingSet MakeSet(int n, bool smooth, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  EmulatorTrainingSet set;
  set.positions = Eigen::Vector2d(0.65, 0.85);
  set.skin_rows = 2;
  set.skin_columns = 2;
  set.ct_inputs = Eigen::MatrixXd::Constant(n, 6, 1.0);
  set.model_inputs = Eigen::MatrixXd::Zero(n, 8);
  set.lift_per_newton.resize(n, 2);
  set.boundary_nodes = {0, 1, 2, 3, 4};
  set.skin.assign(2, Eigen::MatrixXd(n, 12));
  set.boundary.assign(2, Eigen::MatrixXd(n, 15));
  set.skin_anchor_generic_mm = Eigen::MatrixXd::Zero(n, 12);
  for (int i = 0; i < n; ++i) {
    set.patients.push_back(std::to_string(100 + i));
    const Eigen::Vector4d x(0.8 + 0.4 * u(rng), 0.8 + 0.4 * u(rng), 0.8 + 0.4 * u(rng), 10 + 30 * u(rng));
    set.model_inputs.row(i).head<4>() = x.transpose();
    set.ct_inputs.row(i).head<4>() = x.transpose();
    Eigen::SparseMatrix<double, Eigen::RowMajor> ties(4, 5), lift(1, 15);
    for (int v = 0; v < 4; ++v) {
      const double w = 0.2 + 0.6 * u(rng);
      ties.insert(v, v) = w;
      ties.insert(v, v + 1) = 1.0 - w;
    }
    lift.insert(0, 1) = 1.0;
    set.skin_ties.push_back(ties);
    set.lift_ties.push_back(lift);
    for (int p = 0; p < 2; ++p) {
      Eigen::VectorXd nodes(15);
      for (int c = 0; c < 15; ++c) {
        const double t = c / 15.0;
        double value = 0.1 + 0.05 * std::sin(3.0 * t + p);
        if (smooth) {
          const double a = std::log(x(0)) - 0.5 * std::log(x(2)), b = 0.02 * x(3),
                       d = std::log(x(1)) * x(3) / 40.0;
          value *= 1.0 + a * std::cos(2.0 * t) + b * t * t + 0.5 * d * std::sin(5.0 * t);
        }
        nodes(c) = value;
      }
      set.boundary[p].row(i) = nodes.transpose();
      const Eigen::Matrix<double, 5, 3, Eigen::RowMajor> xyz =
          Eigen::Map<const Eigen::Matrix<double, 5, 3, Eigen::RowMajor>>(nodes.data());
      const Eigen::Matrix<double, 4, 3, Eigen::RowMajor> skin = ties * xyz;
      set.skin[p].row(i) = Eigen::Map<const Eigen::RowVectorXd>(skin.data(), 12);
      set.lift_per_newton(i, p) = nodes(1);
    }
  }
  return set;
}

TEST(EmulatorEvaluationTest, TheLeftOutPatientsOwnTiesMakeTheEmulatorExact) {
  const EmulatorTrainingSet set = MakeSet(8, false, 1);
  const EmulatorEvaluation e = EvaluateEmulatorLeaveOneOut(set);
  ASSERT_EQ(e.folds.size(), 8u);
  const auto emulator = e.emulator.Summarise(), mean = e.mean.Summarise(), nearest = e.nearest.Summarise();
  EXPECT_EQ(emulator.cases, 8 * 2 * 8);  // patients x positions x the dissertation's forces
  EXPECT_LT(emulator.relative_l2.max, 1e-9);
  EXPECT_LT(emulator.lift_error.max, 1e-9);
  // The baselines carry other patients' skins: their blends differ, so their skins do.
  EXPECT_GT(mean.relative_l2.mean, 1e-3);
  EXPECT_GT(nearest.relative_l2.mean, 1e-3);
  // The lift is node 0's y in everyone: every method has it.
  EXPECT_LT(mean.lift_error.max, 1e-9);
  EXPECT_EQ(e.input_names.size(), 4u);
  for (const EmulatorFold& fold : e.folds) EXPECT_NE(fold.nearest_patient, fold.patient);
}

TEST(EmulatorEvaluationTest, ASmoothFamilyIsPredictedFarBetterThanTheBaselines) {
  const EmulatorTrainingSet set = MakeSet(24, true, 2);
  std::int64_t calls = 0, last = 0;
  const EmulatorEvaluation e =
      EvaluateEmulatorLeaveOneOut(set, {}, [&](std::int64_t done, std::int64_t total) {
        ++calls;
        last = done;
        EXPECT_EQ(total, 24);
      });
  EXPECT_EQ(calls, 24);
  EXPECT_EQ(last, 24);
  const auto emulator = e.emulator.Summarise(), mean = e.mean.Summarise(), nearest = e.nearest.Summarise();
  EXPECT_LT(emulator.relative_l2.mean, 0.01);
  EXPECT_LT(emulator.relative_l2.mean, 0.2 * mean.relative_l2.mean);
  EXPECT_LT(emulator.relative_l2.mean, 0.5 * nearest.relative_l2.mean);
  EXPECT_GE(emulator.coverage_2sd, 0.9);
  EXPECT_LT(mean.coverage_2sd, 0.0);  // the baselines predict no deviation
}

TEST(EmulatorEvaluationTest, TheNearestPatientIsTheClosestInStandardisedInputs) {
  EmulatorTrainingSet set = MakeSet(9, false, 3);
  // Patient 6 is a near twin of patient 2.
  set.model_inputs.row(6) = set.model_inputs.row(2);
  set.model_inputs(6, 3) += 0.01;
  const EmulatorEvaluation e = EvaluateEmulatorLeaveOneOut(set);
  EXPECT_EQ(e.folds[6].nearest_patient, "102");
  EXPECT_EQ(e.folds[2].nearest_patient, "106");
}

TEST(EmulatorEvaluationTest, BadSetsAndOptionsAreRefused) {
  EXPECT_THROW(EvaluateEmulatorLeaveOneOut(MakeSet(7, false, 4)),
               Error);  // 6 left; 4 inputs and a linear mean need 7
  EmulatorTrainingSet no_nodes = MakeSet(8, false, 5);
  no_nodes.boundary_nodes.clear();
  no_nodes.boundary.clear();
  no_nodes.skin_ties.clear();
  no_nodes.lift_ties.clear();
  try {
    EvaluateEmulatorLeaveOneOut(no_nodes);
    ADD_FAILURE() << "a set without boundary nodes was taken";
  } catch (const Error& error) {
    EXPECT_EQ(error.kind(), ErrorKind::kBadInput);
    EXPECT_NE(std::string(error.what()).find("boundary nodes"), std::string::npos) << error.what();
  }
  EmulatorEvaluationOptions skin_directly;
  skin_directly.through_boundary_nodes = false;
  EXPECT_EQ(EvaluateEmulatorLeaveOneOut(no_nodes, skin_directly).folds.size(), 8u);
  EmulatorEvaluationOptions no_forces;
  no_forces.forces = {};
  EXPECT_THROW(EvaluateEmulatorLeaveOneOut(MakeSet(8, false, 6), no_forces), Error);
  no_forces.forces = {100, -1};
  EXPECT_THROW(EvaluateEmulatorLeaveOneOut(MakeSet(8, false, 6), no_forces), Error);
}

}  // namespace
}  // namespace pectus::planner
