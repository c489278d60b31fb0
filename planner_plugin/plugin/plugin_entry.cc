// pectus planner plugin: the C entry points of planner_api.h. Every function runs its C++ body inside
// Guard(), which turns any exception into a status code and a message: nothing is thrown across the
// boundary and nothing aborts the host.
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <map>
#include <memory>
#include <mutex>
#include <new>
#include <string>

#include "planner_plugin/api/planner_api.h"
#include "planner_plugin/io/fem_dataset_h5.h"
#include "planner_plugin/plugin/planner_session.h"
#include "planner_plugin/plugin/planner_trainer.h"
#include "planner_plugin/plugin/run_fem_dataset.h"
#include "planner_plugin/surrogate/emulator_evaluation.h"
#include "shape/core/error.h"
#include "shape/io/patient_table_io.h"

#ifndef PECTUS_VERSION
#define PECTUS_VERSION "unknown"
#endif

struct PectusPlanner {
  pectus::planner::PlannerSession session;
};

struct PectusPlannerDeformer {
  pectus::planner::SessionDeformer deformer;
};

struct PectusPlannerTrainer {
  PectusPlannerTrainer(const pectus::planner::PatientRibcage& ribcage, const std::string& introducer,
                       std::int64_t capacity_ticks)
      : trainer(ribcage, introducer, capacity_ticks) {}
  pectus::planner::PlannerTrainer trainer;  // refers to itself: made in place, never moved
};

namespace {

using pectus::Error;
using pectus::ErrorKind;

void SetStatus(PectusPlannerStatus* status, std::int32_t code, const std::string& message) {
  if (status == nullptr) return;
  status->code = code;
  std::snprintf(status->message, sizeof(status->message), "%s", message.c_str());
}

// Runs `body`; returns its status code, with the message of any exception in `status`.
template <typename Body>
std::int32_t Guard(PectusPlannerStatus* status, Body&& body) {
  try {
    body();
    SetStatus(status, PECTUS_PLANNER_OK, "");
    return PECTUS_PLANNER_OK;
  } catch (const Error& e) {
    const auto code = static_cast<std::int32_t>(e.kind());
    SetStatus(status, code, e.what());
    return code;
  } catch (const std::bad_alloc&) {
    SetStatus(status, PECTUS_PLANNER_FAILURE, "out of memory");
  } catch (const std::exception& e) {
    SetStatus(status, PECTUS_PLANNER_FAILURE, std::string("planner: ") + e.what());
  } catch (...) {
    SetStatus(status, PECTUS_PLANNER_FAILURE, "planner: unknown failure");
  }
  return PECTUS_PLANNER_FAILURE;
}

template <typename T>
void Require(const T* pointer, const char* name) {
  if (pointer == nullptr) pectus::ThrowUsage(std::string("planner: ") + name + " must not be NULL");
}

void DefaultOptions(PectusPlannerOptions* options) {
  if (options != nullptr) pectus::planner::DefaultPlannerOptions(options);
}

std::int32_t ReadPatient(const char* table_path, const char* patient, PectusPlannerPatient* out,
                         PectusPlannerStatus* status) {
  return Guard(status, [&] {
    Require(table_path, "table_path");
    Require(patient, "patient");
    Require(out, "out");
    const auto rows = pectus::ReadPatientTable(table_path);
    const pectus::PatientTableRow& row = pectus::FindPatient(rows, std::string_view(patient), table_path);
    *out = pectus::planner::PatientFrom(pectus::planner::MeasurementsOf(row), row.haller_index);
  });
}

std::int32_t Create(const PectusPlannerPatient* patient, const PectusPlannerOptions* options,
                    PectusPlanner** out, PectusPlannerStatus* status) {
  return Guard(status, [&] {
    Require(patient, "patient");
    Require(out, "out");
    *out = nullptr;
    const auto settings = pectus::planner::SettingsFrom(options);
    *out = new PectusPlanner{
        pectus::planner::PlannerSession(pectus::planner::MeasurementsFrom(*patient), settings)};
  });
}

void Destroy(PectusPlanner* planner) { delete planner; }

std::int32_t Measurements(const PectusPlanner* planner, PectusPlannerMeasurements* out,
                          PectusPlannerStatus* status) {
  return Guard(status, [&] {
    Require(planner, "planner");
    Require(out, "out");
    *out = planner->session.Measurements();
  });
}

std::int32_t BoneSurface(const PectusPlanner* planner, PectusPlannerMesh* out, PectusPlannerStatus* status) {
  return Guard(status, [&] {
    Require(planner, "planner");
    Require(out, "out");
    *out = planner->session.BoneMesh();
  });
}

std::int32_t SkinSurface(const PectusPlanner* planner, std::int32_t without_deformity, PectusPlannerMesh* out,
                         PectusPlannerStatus* status) {
  return Guard(status, [&] {
    Require(planner, "planner");
    Require(out, "out");
    *out = planner->session.SkinMesh(without_deformity != 0);
  });
}

std::int32_t Landmarks(const PectusPlanner* planner, std::int32_t which, PectusPlannerLandmark* out,
                       std::int32_t capacity, std::int32_t* count, PectusPlannerStatus* status) {
  return Guard(status, [&] {
    Require(planner, "planner");
    Require(count, "count");
    if (capacity > 0) Require(out, "out");
    const pectus::LandmarkSet& set = planner->session.Landmarks(which);
    *count = static_cast<std::int32_t>(set.size());
    for (std::int32_t i = 0; i < capacity && i < *count; ++i) {
      const pectus::Landmark& l = set.items[static_cast<std::size_t>(i)];
      std::snprintf(out[i].label, sizeof(out[i].label), "%s", l.label.c_str());
      for (int c = 0; c < 3; ++c) out[i].position[c] = l.position(c);
    }
  });
}

std::int32_t Solve(const PectusPlanner* planner, const PectusPlannerBar* bars, std::int64_t count,
                   double* bone_positions, double* skin_positions, double* skin_landmarks,
                   PectusPlannerCaseResult* results, PectusPlannerStatus* status) {
  return Guard(status, [&] {
    Require(planner, "planner");
    planner->session.Solve(pectus::planner::LoadsFrom(bars, count), bone_positions, skin_positions,
                           skin_landmarks, results);
  });
}

std::int32_t ForceToLift(const PectusPlanner* planner, const PectusPlannerBar* bars, std::int64_t count,
                         PectusPlannerForceToLift* out, PectusPlannerStatus* status) {
  return Guard(status, [&] {
    Require(planner, "planner");
    if (count > 0) Require(out, "out");
    std::vector<pectus::planner::BarLoad> loads = pectus::planner::LoadsFrom(bars, count);
    for (auto& load : loads) load.force_n = 1.0;
    const auto lift = planner->session.fem().ForceToLiftSternum(loads);
    for (std::size_t i = 0; i < lift.size(); ++i) out[i] = {lift[i].lift_per_newton_mm, lift[i].force_n};
  });
}

pectus::planner::BarResponseBasisOptions BasisOptionsFrom(const PectusPlannerBasisOptions* options) {
  pectus::planner::BarResponseBasisOptions o;
  if (options != nullptr) {
    if (options->tolerance_mm != 0) o.tolerance_mm = options->tolerance_mm;
    if (options->max_force_n != 0) o.max_force_n = options->max_force_n;
  }
  return o;
}

PectusPlannerBasisSummary SummaryOf(const pectus::planner::BarResponseBasis& basis, double max_force_n,
                                    double seconds) {
  return {basis.rank(),
          basis.num_contact_nodes(),
          basis.num_points(),
          static_cast<std::int64_t>(basis.bytes()),
          basis.truncation_bound_mm_per_n() * max_force_n,
          seconds};
}

std::int32_t WriteDataset(const char* table_path, const char* output_path,
                          const PectusPlannerOptions* options, const PectusPlannerBasisOptions* basis,
                          PectusPlannerProgressFn progress, void* progress_user,
                          PectusPlannerDatasetSummary* out, PectusPlannerStatus* status) {
  return Guard(status, [&] {
    Require(table_path, "table_path");
    Require(output_path, "output_path");
    const pectus::planner::BarResponseBasisOptions basis_options = BasisOptionsFrom(basis);
    const auto summary = pectus::planner::RunFemDataset(
        table_path, output_path, pectus::planner::SettingsFrom(options),
        [&](std::int64_t done, std::int64_t total) {
          if (progress != nullptr) progress(progress_user, done, total);
        },
        basis != nullptr ? &basis_options : nullptr);
    if (out != nullptr) {
      *out = {summary.patients, summary.load_cases, summary.results, summary.surface_nodes,
              summary.timings_s.Total()};
    }
  });
}

// ---- version 6: the FE dataset one patient at a time -----------------------------------------------------

// The generic ribcage of `settings`, built once per process and options (a farm's rank makes many parts).
std::shared_ptr<const pectus::planner::GenericRibcage> CachedGenericRibcage(
    const PectusPlannerOptions* options, const pectus::planner::PlannerSettings& settings) {
  PectusPlannerOptions o{};
  if (options != nullptr) {
    o = *options;
  } else {
    pectus::planner::DefaultPlannerOptions(&o);
  }
  char key[512];
  std::snprintf(key, sizeof(key), "%a %a %a %a %a %a %a %a %d %a %d %d", o.sternum_youngs_modulus_mpa,
                o.sternum_poisson_ratio, o.rib_youngs_modulus_mpa, o.rib_poisson_ratio,
                o.cartilage_youngs_modulus_mpa, o.cartilage_poisson_ratio, o.contact_width_mm,
                o.rib_cell_length_mm, o.sternum_cells_along, o.soft_tissue_mm, o.skin_rows, o.skin_columns);
  static std::mutex mutex;
  static std::map<std::string, std::shared_ptr<const pectus::planner::GenericRibcage>> cache;
  const std::lock_guard<std::mutex> lock(mutex);  // the others wait: they need the same ribcage
  auto& generic = cache[key];
  if (!generic) {
    generic = std::make_shared<const pectus::planner::GenericRibcage>(
        pectus::planner::BuildGenericRibcage(settings.generic));
  }
  return generic;
}

std::int32_t WriteDatasetPart(const char* table_path, std::int64_t row, const char* part_path,
                              const PectusPlannerOptions* options, const PectusPlannerBasisOptions* basis,
                              PectusPlannerDatasetSummary* out, PectusPlannerStatus* status) {
  return Guard(status, [&] {
    Require(table_path, "table_path");
    Require(part_path, "part_path");
    const auto start = std::chrono::steady_clock::now();
    const auto rows = pectus::ReadPatientTable(table_path);
    if (row < 0 || row >= static_cast<std::int64_t>(rows.size())) {
      pectus::ThrowUsage("planner: row " + std::to_string(row) + " is not a row of " + table_path + " (" +
                         std::to_string(rows.size()) + " patients)");
    }
    const pectus::planner::PlannerSettings settings = pectus::planner::SettingsFrom(options);
    const pectus::planner::BarResponseBasisOptions basis_options = BasisOptionsFrom(basis);
    const auto setup = std::chrono::steady_clock::now();
    const auto generic = CachedGenericRibcage(options, settings);  // built by the process's first call
    const auto setup_end = std::chrono::steady_clock::now();
    const auto summary =
        pectus::planner::RunFemDatasetPart(*generic, rows[static_cast<std::size_t>(row)], part_path, settings,
                                           basis != nullptr ? &basis_options : nullptr);
    // The part's own time: without the generic ribcage, which the process made (or waited for) once.
    const double seconds =
        std::chrono::duration<double>((std::chrono::steady_clock::now() - start) - (setup_end - setup))
            .count();
    if (out != nullptr)
      *out = {summary.patients, summary.load_cases, summary.results, summary.surface_nodes, seconds};
  });
}

std::int32_t AssembleDataset(const char* const* part_paths, std::int64_t count, const char* output_path,
                             PectusPlannerDatasetSummary* out, PectusPlannerStatus* status) {
  return Guard(status, [&] {
    Require(output_path, "output_path");
    if (count > 0) Require(part_paths, "part_paths");
    const auto start = std::chrono::steady_clock::now();
    std::vector<std::filesystem::path> parts;
    for (std::int64_t i = 0; i < count; ++i) {
      Require(part_paths[i], "a part path");
      parts.emplace_back(part_paths[i]);
    }
    const auto a = pectus::planner::AssembleFemDataset(parts, output_path);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (out != nullptr) *out = {count, a.load_cases, count * a.load_cases, a.surface_nodes, seconds};
  });
}

std::int32_t BuildBasis(PectusPlanner* planner, const PectusPlannerBasisOptions* options,
                        PectusPlannerBasisSummary* out, PectusPlannerStatus* status) {
  return Guard(status, [&] {
    Require(planner, "planner");
    const pectus::planner::BarResponseBasisOptions o = BasisOptionsFrom(options);
    const auto& basis = planner->session.BuildBasis(o);
    if (out != nullptr) *out = SummaryOf(basis, o.max_force_n, basis.timings_s().Total());
  });
}

std::int32_t LoadBasis(PectusPlanner* planner, const char* dataset_path, PectusPlannerBasisSummary* out,
                       PectusPlannerStatus* status) {
  return Guard(status, [&] {
    Require(planner, "planner");
    Require(dataset_path, "dataset_path");
    const auto start = std::chrono::steady_clock::now();
    planner->session.LoadBasis(
        pectus::planner::ReadStoredResponseBasis(dataset_path, planner->session.ribcage().patient),
        dataset_path);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const pectus::planner::BarResponseBasis& basis = *planner->session.basis();
    // The force the tolerance was stated for is not stored; the bound is given per 2000 N, the default.
    if (out != nullptr) *out = SummaryOf(basis, 2000.0, seconds);
  });
}

std::int32_t CreateDeformer(const PectusPlanner* planner, PectusPlannerDeformer** out,
                            PectusPlannerStatus* status) {
  return Guard(status, [&] {
    Require(planner, "planner");
    Require(out, "out");
    *out = nullptr;
    *out = new PectusPlannerDeformer{pectus::planner::SessionDeformer(planner->session)};
  });
}

void DestroyDeformer(PectusPlannerDeformer* deformer) { delete deformer; }

// The real-time calls: no Guard (its messages allocate); a fixed reason copied into the status.
std::int32_t RealTimeFailure(PectusPlannerStatus* status, const char* why) noexcept {
  if (status != nullptr) {
    status->code = PECTUS_PLANNER_USAGE;
    std::snprintf(status->message, sizeof(status->message), "planner: %s", why);
  }
  return PECTUS_PLANNER_USAGE;
}

std::int32_t RealTimeOk(PectusPlannerStatus* status) noexcept {
  if (status != nullptr) {
    status->code = PECTUS_PLANNER_OK;
    status->message[0] = '\0';
  }
  return PECTUS_PLANNER_OK;
}

pectus::planner::BarLoad LoadOf(const PectusPlannerBar& bar) noexcept {
  return {bar.position, bar.position_in_mm != 0, bar.force_n};
}

std::int32_t Deform(PectusPlannerDeformer* deformer, const PectusPlannerBar* bar, double* bone_positions,
                    double* skin_positions, double* skin_landmarks, double* sternum_lift_mm,
                    PectusPlannerStatus* status) noexcept {
  if (deformer == nullptr || bar == nullptr)
    return RealTimeFailure(status, "deformer and bar must not be NULL");
  const char* why = "";
  if (!deformer->deformer.Deform(LoadOf(*bar), bone_positions, skin_positions, skin_landmarks,
                                 sternum_lift_mm, &why)) {
    return RealTimeFailure(status, why);
  }
  return RealTimeOk(status);
}

std::int32_t LiftForce(PectusPlannerDeformer* deformer, const PectusPlannerBar* bar, double lift_mm,
                       double* force_n, PectusPlannerStatus* status) noexcept {
  if (deformer == nullptr || bar == nullptr || force_n == nullptr) {
    return RealTimeFailure(status, "deformer, bar and force_n must not be NULL");
  }
  const char* why = "";
  const double force = deformer->deformer.LiftForce(LoadOf(*bar), lift_mm, &why);
  if (!std::isfinite(force)) return RealTimeFailure(status, why);
  *force_n = force;
  return RealTimeOk(status);
}

std::int32_t BasisModes(const PectusPlanner* planner, float* modes, std::int64_t capacity, std::int64_t* rows,
                        std::int64_t* rank, PectusPlannerStatus* status) {
  return Guard(status, [&] {
    Require(planner, "planner");
    const pectus::planner::BarResponseBasis* basis = planner->session.basis();
    if (basis == nullptr)
      pectus::ThrowUsage("basis_modes: the planner has no response basis yet; build it first (build_basis)");
    const std::int64_t n = 3 * basis->num_points(), r = basis->rank();
    if (rows != nullptr) *rows = n;
    if (rank != nullptr) *rank = r;
    if (modes == nullptr) return;
    if (capacity < n * r) {
      pectus::ThrowUsage("basis_modes: the modes need " + std::to_string(n * r) + " floats, capacity is " +
                         std::to_string(capacity));
    }
    basis->CopyModes(modes);
  });
}

std::int32_t BasisCoefficients(PectusPlannerDeformer* deformer, const PectusPlannerBar* bar,
                               double* coefficients, double* lift_per_n,
                               PectusPlannerStatus* status) noexcept {
  if (deformer == nullptr || bar == nullptr)
    return RealTimeFailure(status, "deformer and bar must not be NULL");
  const char* why = "";
  if (!deformer->deformer.CoefficientsPerNewton(LoadOf(*bar), coefficients, lift_per_n, &why))
    return RealTimeFailure(status, why);
  return RealTimeOk(status);
}

PectusPlannerEmulatorFigures FiguresOf(const pectus::planner::EmulatorErrors& errors) {
  const auto s = errors.Summarise();
  return {s.cases,
          s.small_lift_cases,
          s.skin_rms.mean,
          s.skin_rms.max,
          s.skin_rms.within,
          s.skin_p95.mean,
          s.skin_p95.max,
          s.skin_p95.within,
          s.relative_l2.mean,
          s.relative_l2.max,
          s.relative_l2.within,
          s.small_lift_error.mean,
          s.small_lift_error.max,
          s.small_lift_error.within,
          s.lift_error.mean,
          s.lift_error.max,
          s.coverage_2sd,
          s.worst_skin_rms_patient,
          s.worst_relative_l2_patient,
          s.worst_lift_patient};
}

std::int32_t EvaluateEmulator(const char* table_path, const char* patients,
                              const PectusPlannerOptions* options,
                              const PectusPlannerEmulatorOptions* emulator, PectusPlannerProgressFn progress,
                              void* progress_user, PectusPlannerEmulatorEvaluation* out,
                              PectusPlannerEmulatorPatient* per_patient, std::int64_t capacity,
                              PectusPlannerStatus* status) {
  return Guard(status, [&] {
    using namespace pectus::planner;
    Require(table_path, "table_path");
    if (per_patient != nullptr && capacity < 0) pectus::ThrowUsage("planner: capacity must not be negative");
    const PectusPlannerEmulatorOptions e = emulator != nullptr ? *emulator : PectusPlannerEmulatorOptions{};
    EmulatorEvaluationOptions evaluation;
    if (e.inputs < 0 || e.inputs > 3) pectus::ThrowUsage("planner: emulator inputs must be 0 to 3");
    if (e.scale < 0 || e.scale > 2) pectus::ThrowUsage("planner: emulator scale must be 0 to 2");
    if (e.max_components < 0) pectus::ThrowUsage("planner: emulator max_components must not be negative");
    evaluation.inputs = std::array{EmulatorInputs::kMapLog, EmulatorInputs::kCt, EmulatorInputs::kCtLog,
                                   EmulatorInputs::kCtLogMapLog}[static_cast<std::size_t>(e.inputs)];
    evaluation.emulator.scale = std::array{ResponseScale::kLift, ResponseScale::kNorm,
                                           ResponseScale::kNone}[static_cast<std::size_t>(e.scale)];
    if (e.max_components > 0) evaluation.emulator.max_components = e.max_components;
    if (e.explained_fraction != 0) evaluation.emulator.explained_fraction = e.explained_fraction;
    evaluation.through_boundary_nodes = e.learn_skin == 0;
    std::string why;
    if (!evaluation.IsValid(&why)) pectus::ThrowUsage("planner: emulator options: " + why);

    // The patients: the table's, or those named, in the table's order.
    std::vector<pectus::PatientTableRow> rows = pectus::ReadPatientTable(table_path);
    if (patients != nullptr) {
      std::vector<int> named;
      const std::string list(patients);
      for (std::size_t from = 0; from <= list.size();) {
        const std::size_t comma = std::min(list.find(',', from), list.size());
        const std::string id = list.substr(from, comma - from);
        if (!id.empty()) named.push_back(pectus::FindPatient(rows, std::string_view(id), table_path).patient);
        from = comma + 1;
      }
      if (named.empty())
        pectus::ThrowUsage(std::string("planner: patients '") + patients + "' names no patient");
      std::sort(named.begin(), named.end());
      if (std::adjacent_find(named.begin(), named.end()) != named.end()) {
        pectus::ThrowUsage(std::string("planner: patients '") + patients + "' names a patient twice");
      }
      std::erase_if(rows, [&](const pectus::PatientTableRow& row) {
        return !std::binary_search(named.begin(), named.end(), row.patient);
      });
    }
    const auto n = static_cast<std::int64_t>(rows.size());
    if (n < EmulatorEvaluationMinimumPatients(evaluation)) {
      pectus::ThrowUsage("planner: " + std::to_string(n) +
                         " patients; leaving one out with these inputs needs at least " +
                         std::to_string(EmulatorEvaluationMinimumPatients(evaluation)));
    }
    EmulatorTrainingSetOptions training;
    training.boundary_nodes = evaluation.through_boundary_nodes;
    training.settings = SettingsFrom(options);
    auto report = [&](std::int64_t done) {
      if (progress != nullptr) progress(progress_user, done, 2 * n);
    };
    const EmulatorTrainingSet set =
        BuildEmulatorTrainingSet(rows, training, [&](std::int64_t done, std::int64_t) { report(done); });
    const EmulatorEvaluation result = EvaluateEmulatorLeaveOneOut(
        set, evaluation, [&](std::int64_t done, std::int64_t) { report(n + done); });
    if (out != nullptr) {
      *out = {n,
              set.num_positions(),
              static_cast<std::int64_t>(evaluation.forces.size()),
              set.num_skin_vertices(),
              set.timings_s.Total(),
              result.seconds,
              FiguresOf(result.emulator),
              FiguresOf(result.nearest),
              FiguresOf(result.mean)};
    }
    if (per_patient != nullptr) {
      for (std::int64_t i = 0; i < std::min(capacity, n); ++i) {
        const EmulatorFold& fold = result.folds[static_cast<std::size_t>(i)];
        PectusPlannerEmulatorPatient& p = per_patient[i];
        p = {};
        std::snprintf(p.id, sizeof(p.id), "%s", fold.patient.c_str());
        std::snprintf(p.nearest_patient, sizeof(p.nearest_patient), "%s", fold.nearest_patient.c_str());
        p.emulator = FiguresOf(fold.emulator);
        p.fit_seconds = fold.fit_seconds;
        double components = 0;
        for (int c : fold.components) components += c;
        p.components_mean =
            fold.components.empty() ? 0.0 : components / static_cast<double>(fold.components.size());
      }
    }
  });
}

// ---- version 5: the trainer -----------------------------------------------------------------------------

using pectus::planner::PlannerTrainer;

PectusPlannerSpace SpaceOf(const pectus::trainer::IntercostalSpace& s) { return {s.side, s.number}; }

void Copy3(const Eigen::Vector3d& v, double* out) {
  for (int k = 0; k < 3; ++k) out[k] = v[k];
}

std::int32_t TrainerCreate(const PectusPlanner* planner, const char* introducer, std::int64_t capacity_ticks,
                           PectusPlannerTrainer** out, PectusPlannerStatus* status) {
  return Guard(status, [&] {
    Require(planner, "planner");
    Require(out, "out");
    *out = nullptr;
    *out = new PectusPlannerTrainer(planner->session.ribcage(), introducer != nullptr ? introducer : "medium",
                                    capacity_ticks);
  });
}

void TrainerDestroy(PectusPlannerTrainer* trainer) { delete trainer; }

std::int32_t TrainerMesh(const PectusPlannerTrainer* trainer, std::int32_t part, PectusPlannerMesh* out,
                         PectusPlannerStatus* status) {
  return Guard(status, [&] {
    Require(trainer, "trainer");
    Require(out, "out");
    const pectus::trainer::TrainerScene& scene = trainer->trainer.scene();
    auto view = [](const pectus::Points3& v, const pectus::Faces3& f, const std::int32_t* labels) {
      return PectusPlannerMesh{v.rows(), v.data(), f.rows(), f.data(), labels};
    };
    switch (part) {
      case 0: *out = view(scene.bone_vertices, scene.bone_faces, scene.bone_parts.data()); return;
      case 1:
        *out = view(scene.pericardium.mesh.vertices.positions, scene.pericardium.mesh.faces, nullptr);
        return;
      case 2:
        *out = view(scene.right_lung.mesh.vertices.positions, scene.right_lung.mesh.faces, nullptr);
        return;
      case 3:
        *out = view(scene.left_lung.mesh.vertices.positions, scene.left_lung.mesh.faces, nullptr);
        return;
      default:
        pectus::ThrowUsage("trainer_mesh: part " + std::to_string(part) +
                           " is none of 0 bones, 1 pericardium, 2 right lung, 3 left lung");
    }
  });
}

std::int32_t TrainerTunnel(const PectusPlannerTrainer* trainer, PectusPlannerTunnel* out, double* points,
                           std::int64_t capacity, PectusPlannerStatus* status) {
  return Guard(status, [&] {
    Require(trainer, "trainer");
    const pectus::trainer::PlannedTunnel& t = trainer->trainer.scene().tunnel;
    const std::int64_t n = t.points.rows();
    if (points != nullptr && capacity < n) {
      pectus::ThrowUsage("trainer_tunnel: the tunnel has " + std::to_string(n) + " points, capacity is " +
                         std::to_string(capacity));
    }
    if (out != nullptr) {
      PectusPlannerTunnel o{};
      Copy3(t.entry_port, o.entry_port_mm);
      Copy3(t.exit_port, o.exit_port_mm);
      o.entry = SpaceOf(t.entry);
      o.exit = SpaceOf(t.exit);
      Copy3(trainer->trainer.scope_port(), o.scope_port_mm);
      o.level_z_mm = t.level_z_mm;
      o.length_mm = t.length_mm;
      o.num_points = n;
      *out = o;
    }
    if (points != nullptr) std::copy(t.points.data(), t.points.data() + 3 * n, points);
  });
}

std::int32_t TrainerReset(PectusPlannerTrainer* trainer, PectusPlannerStatus* status) {
  return Guard(status, [&] {
    Require(trainer, "trainer");
    trainer->trainer.Reset();
  });
}

std::int32_t TrainerTick(PectusPlannerTrainer* trainer, const PectusPlannerDeviceState* state,
                         PectusPlannerTrainerTick* out, PectusPlannerStatus* status) noexcept {
  if (trainer == nullptr || state == nullptr)
    return RealTimeFailure(status, "trainer and state must not be NULL");
  const char* why = "";
  if (!trainer->trainer.Tick(*state, out, &why)) return RealTimeFailure(status, why);
  return RealTimeOk(status);
}

std::int32_t TrainerStart(PectusPlannerTrainer* trainer, const PectusPlannerDevice* device, double rate_hz,
                          PectusPlannerStatus* status) {
  return Guard(status, [&] {
    Require(trainer, "trainer");
    Require(device, "device");
    trainer->trainer.Start(*device, rate_hz == 0 ? 1000.0 : rate_hz);
  });
}

std::int32_t TrainerStop(PectusPlannerTrainer* trainer, PectusPlannerLoopStatistics* out,
                         PectusPlannerStatus* status) {
  return Guard(status, [&] {
    Require(trainer, "trainer");
    const pectus::trainer::ServoLoopStatistics s = trainer->trainer.Stop();
    if (out != nullptr) {
      *out = {s.ticks,         s.late_ticks,  s.period_mean_ms, s.period_p50_ms, s.period_p99_ms,
              s.period_max_ms, s.tick_p50_us, s.tick_p99_us,    s.tick_max_us};
    }
  });
}

std::int32_t TrainerLatest(const PectusPlannerTrainer* trainer, PectusPlannerTrainerTick* out,
                           PectusPlannerStatus* status) {
  return Guard(status, [&] {
    Require(trainer, "trainer");
    Require(out, "out");
    if (!trainer->trainer.Latest(out)) pectus::ThrowUsage("trainer_latest: the session has no tick yet");
  });
}

PectusPlannerTrainerScore ScoreOf(const pectus::trainer::SessionScore& s, std::int64_t ticks) {
  PectusPlannerTrainerScore o{};
  o.ticks = ticks;
  o.min_pericardium_distance_mm = s.min_pericardium_distance_mm;
  o.time_near_pericardium_s = s.time_near_pericardium_s;
  o.pericardial_contacts = s.pericardial_contacts;
  o.peak_pericardium_force_n = s.peak_pericardium_force_n;
  o.peak_force_n = s.peak_force_n;
  o.path_length_mm = s.path_length_mm;
  o.rms_tunnel_deviation_mm = s.rms_tunnel_deviation_mm;
  o.entry = SpaceOf(s.entry);
  o.exit = SpaceOf(s.exit);
  o.entry_as_planned = s.entry_as_planned ? 1 : 0;
  o.exit_as_planned = s.exit_as_planned ? 1 : 0;
  o.total_time_s = s.total_time_s;
  o.score = s.score;
  return o;
}

std::int32_t TrainerScore(const PectusPlannerTrainer* trainer, PectusPlannerTrainerScore* out,
                          PectusPlannerStatus* status) {
  return Guard(status, [&] {
    Require(trainer, "trainer");
    Require(out, "out");
    const pectus::trainer::SessionRecord record = trainer->trainer.RecordSoFar();
    if (record.samples.size() < 2) pectus::ThrowUsage("trainer_score: the session has fewer than two ticks");
    *out = ScoreOf(pectus::trainer::ScoreSession(trainer->trainer.scene(), record),
                   static_cast<std::int64_t>(record.samples.size()));
  });
}

std::int32_t TrainerWriteRecord(const PectusPlannerTrainer* trainer, const char* path,
                                PectusPlannerStatus* status) {
  return Guard(status, [&] {
    Require(trainer, "trainer");
    Require(path, "path");
    pectus::trainer::WriteSessionRecord(path, trainer->trainer.RecordSoFar());
  });
}

std::int32_t TrainerReplay(const PectusPlannerTrainer* trainer, const char* path,
                           PectusPlannerTrainerScore* out, PectusPlannerStatus* status) {
  return Guard(status, [&] {
    Require(trainer, "trainer");
    Require(path, "path");
    Require(out, "out");
    const pectus::trainer::SessionRecord record = pectus::trainer::ReadSessionRecord(path);
    const pectus::trainer::TrainerScene& scene = trainer->trainer.scene();
    if (record.patient != scene.patient) {
      pectus::ThrowBadInput(path, "the record is patient '" + record.patient + "''s, this trainer patient '" +
                                      scene.patient + "''s");
    }
    if (record.samples.size() < 2) pectus::ThrowBadInput(path, "the record has fewer than two ticks");
    const pectus::trainer::SessionRecord replayed = pectus::trainer::ReplaySession(scene, record);
    *out = ScoreOf(pectus::trainer::ScoreSession(scene, replayed),
                   static_cast<std::int64_t>(replayed.samples.size()));
  });
}

std::int32_t TrainerScopeView(const PectusPlannerTrainer* trainer, const double* orientation_wxyz,
                              const double* target_mm, double insertion_mm, PectusPlannerScopeView* out,
                              PectusPlannerStatus* status) {
  return Guard(status, [&] {
    Require(trainer, "trainer");
    Require(out, "out");
    if (orientation_wxyz != nullptr) {
      const Eigen::Quaterniond q(orientation_wxyz[0], orientation_wxyz[1], orientation_wxyz[2],
                                 orientation_wxyz[3]);
      *out = trainer->trainer.ScopeView(&q, Eigen::Vector3d::Zero(), insertion_mm);
      return;
    }
    Eigen::Vector3d target;
    if (target_mm != nullptr) {
      target = Eigen::Vector3d(target_mm[0], target_mm[1], target_mm[2]);
    } else {
      PectusPlannerTrainerTick latest{};
      if (!trainer->trainer.Latest(&latest))
        pectus::ThrowUsage("trainer_scope_view: no target and no tick yet to aim at");
      target = Eigen::Vector3d(latest.proxy_mm[0], latest.proxy_mm[1], latest.proxy_mm[2]);
    }
    *out = trainer->trainer.ScopeView(nullptr, target, insertion_mm);
  });
}

const PectusPlannerInterface kInterface = {
    PECTUS_PLANNER_INTERFACE_VERSION,
    sizeof(PectusPlannerInterface),
    "pectus planner " PECTUS_VERSION " (patient ribcage from CT measurements, quadratic tetrahedra, CHOLMOD)",
    DefaultOptions,
    ReadPatient,
    Create,
    Destroy,
    Measurements,
    BoneSurface,
    SkinSurface,
    Landmarks,
    Solve,
    ForceToLift,
    WriteDataset,
    BuildBasis,
    LoadBasis,
    CreateDeformer,
    DestroyDeformer,
    Deform,
    LiftForce,
    EvaluateEmulator,
    BasisModes,
    BasisCoefficients,
    TrainerCreate,
    TrainerDestroy,
    TrainerMesh,
    TrainerTunnel,
    TrainerReset,
    TrainerTick,
    TrainerStart,
    TrainerStop,
    TrainerLatest,
    TrainerScore,
    TrainerWriteRecord,
    TrainerReplay,
    TrainerScopeView,
    WriteDatasetPart,
    AssembleDataset,
};

}  // namespace

extern "C" __attribute__((visibility("default"))) const PectusPlannerInterface* pectus_planner_interface(
    void) {
  return &kInterface;
}
