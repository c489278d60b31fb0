// pectus planner: the response emulator judged the way the issue asks (issue 14): leave one *patient* out
// at a time. For each patient of a training set the emulator is fitted on the others and predicts the
// patient's load cases (every position of the set x the dissertation's forces) from its measurements
// alone; the prediction is compared with the patient's own FE solution. Beside it, on the same folds, two
// baselines that need no learning: the nearest patient (in standardised inputs) and the mean response.
// A random split of the cases (the dissertation's) would put every patient in training and test at once;
// this evaluation never does.
//
// Used by `pectus surrogate evaluate` (through the plugin) and by tests/benchmarks/emulator_benchmark.cc
// (which adds the dissertation's network in the same run).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "planner_plugin/surrogate/emulator_training_set.h"
#include "planner_plugin/surrogate/response_emulator.h"

namespace pectus::planner {

/// The patient parameters the emulator and the baselines are given.
enum class EmulatorInputs {
  kMapLog,       ///< the fitted patient map: log scale x, y, z and the sternum's depression (default)
  kCt,           ///< the six CT measurements as measured (true size)
  kCtLog,        ///< the same with the logarithms of width, depth and sternal length
  kCtLogMapLog,  ///< both
};

/// The columns of `kind` for every patient of `set` (n by p), and their names in `names` if not null.
Eigen::MatrixXd EmulatorInputMatrix(const EmulatorTrainingSet& set, EmulatorInputs kind,
                                    std::vector<std::string>* names = nullptr);

/// A method's errors over its test cases. A case is one (patient, position, force); u its displacement of
/// the skin grid's vertices (mm).
/// - skin RMS and skin p95: the RMS and the 95th percentile over the vertices of |u_pred,v - u_fe,v|, on
///   the cases whose FE sternal lift is at most `kSmallLiftMm`;
/// - relative L2: |u_pred - u_fe| / |u_fe| over every coordinate, all cases;
/// - lift error: |lift_pred - lift_fe|, on the small-lift cases and on all;
/// - 2 sigma coverage (methods with a predicted standard deviation): the fraction of every coordinate of
///   every case whose error is within twice the predicted deviation.
class EmulatorErrors {
 public:
  static constexpr double kSmallLiftMm = 40.0;

  /// One case: predicted and FE displacements (3 #vertices, mm), the predicted standard deviation (the
  /// same size, or empty), the predicted and FE lifts (mm), and which patient (an index) it belongs to.
  void Add(const Eigen::VectorXd& predicted, const Eigen::VectorXd& fe, const Eigen::VectorXd& sd,
           double lift_predicted, double lift_fe, int patient);
  /// Appends `other`'s cases.
  void Merge(const EmulatorErrors& other);

  /// One error's figures over its cases: mean, 95th percentile (linear between order statistics), maximum,
  /// and the fraction of cases within the limit for it (1 mm, 2 mm, 5 %, 1 mm; none for the lift
  /// over all cases: 0).
  struct Figures {
    double mean = 0, p95 = 0, max = 0, within = 0;
  };
  /// The summary: every error's figures, the coverage and the worst patients.
  struct Summary {
    std::int64_t cases = 0, small_lift_cases = 0;
    Figures skin_rms;          ///< per small-lift case, the RMS over the skin (mm); within 1 mm
    Figures skin_p95;          ///< per small-lift case, the 95th percentile over the skin (mm); within 2 mm
    Figures relative_l2;       ///< per case, |u_pred - u_fe| / |u_fe| (a fraction); within 5 %
    Figures small_lift_error;  ///< per small-lift case, the lift's error (mm); within 1 mm
    Figures lift_error;        ///< per case, the lift's error (mm)
    double coverage_2sd = -1;  ///< -1 without predicted deviations
    /// The patient (an index) of the largest skin RMS, relative L2 and lift error; -1 without cases.
    int worst_skin_rms_patient = -1, worst_relative_l2_patient = -1, worst_lift_patient = -1;
  };
  Summary Summarise() const;

  std::int64_t cases() const { return static_cast<std::int64_t>(relative_l2_.size()); }

 private:
  std::vector<double> rms_small_, p95_small_, lift_error_small_;
  std::vector<int> patient_small_;
  std::vector<double> relative_l2_, lift_error_;
  std::vector<int> patient_;
  double within_2sd_ = 0, coordinates_ = 0;
};

/// How the evaluation runs.
struct EmulatorEvaluationOptions {
  /// The emulator's settings (ResponseEmulatorOptions' defaults).
  ResponseEmulatorOptions emulator;
  /// Its inputs. Default kMapLog (docs/benchmarks/emulator.md: the fitted map beats the CT columns).
  EmulatorInputs inputs = EmulatorInputs::kMapLog;
  /// Learn the mesh's boundary nodes and carry them to the skin and the lift through the left-out
  /// patient's own ties (true, default; needs a set built with boundary nodes), or learn the skin grid and
  /// the lift directly (false).
  bool through_boundary_nodes = true;
  /// The bar forces of every position, N (> 0). Default: the dissertation's eight (50 to 2000 N).
  std::vector<double> forces = {50, 70, 100, 200, 400, 800, 1500, 2000};
  bool IsValid(std::string* why) const;
};

/// The fewest patients a leave-one-out evaluation with `options` takes: each fold trains on n - 1, which
/// must reach the emulator's least (min_patients) and, with a linear mean, the inputs' count plus three.
Eigen::Index EmulatorEvaluationMinimumPatients(const EmulatorEvaluationOptions& options);

/// One left-out patient.
struct EmulatorFold {
  std::string patient;
  EmulatorErrors emulator, nearest, mean;
  Eigen::VectorXd lift_per_newton_fe, lift_per_newton_emulator;  ///< per position, mm/N
  /// Per position, the emulator's own lift process (mm/N), before the nodes are carried through the
  /// patient's ties (which give lift_per_newton_emulator); the same when the skin is learnt directly.
  Eigen::VectorXd lift_per_newton_process;
  std::string nearest_patient;
  std::vector<int> components;  ///< principal components kept per position
  double fit_seconds = 0;
};

/// The whole evaluation.
struct EmulatorEvaluation {
  std::vector<std::string> input_names;
  std::vector<EmulatorFold> folds;         ///< one per patient, in the set's order
  EmulatorErrors emulator, nearest, mean;  ///< every fold's cases together
  double seconds = 0;
};

/// Leaves each patient of `set` out in turn (folds in parallel on the OpenMP threads, each fold on one).
/// `progress(done, total)` is called after each fold, from one thread at a time. Throws Error(kUsage) for
/// invalid options or a set too small for the emulator (options.emulator.min_patients + 1 patients), and
/// Error(kBadInput) for a set without boundary nodes when they are asked for; an emulator that fails on a
/// fold fails the evaluation with the patient's id.
EmulatorEvaluation EvaluateEmulatorLeaveOneOut(
    const EmulatorTrainingSet& set, const EmulatorEvaluationOptions& options = {},
    const std::function<void(std::int64_t, std::int64_t)>& progress = {});

}  // namespace pectus::planner
