#include "planner_plugin/host/planner_client.h"

#include <algorithm>
#include <cstdio>

#include "shape/core/error.h"
#include "shape/io/patient_table_io.h"

namespace pectus::planner {

void ThrowIfFailed(std::int32_t code, const PectusPlannerStatus& status) {
  if (code == PECTUS_PLANNER_OK) return;
  const std::string message = status.message[0] != '\0' ? status.message : "the planner plugin failed";
  switch (code) {
    case PECTUS_PLANNER_USAGE: throw Error(ErrorKind::kUsage, message);
    case PECTUS_PLANNER_BAD_INPUT: throw Error(ErrorKind::kBadInput, message);
    default: throw Error(ErrorKind::kFailure, message);
  }
}

std::string BarPlacement::Name() const {
  char text[96];
  std::snprintf(text, sizeof(text), position_in_mm ? "%.1f mm, %.0f N" : "%.3g L, %.0f N", position, force_n);
  return text;
}

double LinearRangeLiftMm(double depression_mm) { return 2.0 * std::max(10.0, depression_mm); }

namespace {

TriangleMesh ToMesh(const PectusPlannerMesh& m) {
  TriangleMesh mesh;
  mesh.vertices.positions = Eigen::Map<const Points3>(m.vertices, m.num_vertices, 3);
  mesh.faces = Eigen::Map<const Faces3>(m.faces, m.num_faces, 3);
  return mesh;
}

PectusPlannerBar ToBar(const BarPlacement& b) { return {b.position, b.position_in_mm ? 1 : 0, b.force_n}; }

}  // namespace

PlannerClient::PlannerClient(const PlannerPlugin& plugin, const PectusPlannerPatient& patient,
                             const PectusPlannerOptions& options)
    : api_(&plugin.api()), patient_(patient), options_(options) {
  PectusPlannerStatus status{};
  ThrowIfFailed(api_->create(&patient, &options, &planner_, &status), status);
  try {
    ThrowIfFailed(api_->measurements(planner_, &measurements_, &status), status);
    PectusPlannerMesh mesh{};
    ThrowIfFailed(api_->bone_surface(planner_, &mesh, &status), status);
    bone_ = ToMesh(mesh);
    bone_regions_ = Eigen::Map<const Eigen::VectorXi>(mesh.face_labels, mesh.num_faces);
    ThrowIfFailed(api_->skin_surface(planner_, 0, &mesh, &status), status);
    skin_ = ToMesh(mesh);
    ThrowIfFailed(api_->skin_surface(planner_, 1, &mesh, &status), status);
    reference_skin_ = Eigen::Map<const Points3>(mesh.vertices, mesh.num_vertices, 3);
    bone_landmarks_ = Landmarks(PECTUS_PLANNER_BONE_LANDMARKS);
    skin_landmarks_ = Landmarks(PECTUS_PLANNER_SKIN_LANDMARKS);
    reference_landmarks_ = Landmarks(PECTUS_PLANNER_REFERENCE_LANDMARKS);
  } catch (...) {
    api_->destroy(planner_);
    throw;
  }
}

PlannerClient::~PlannerClient() {
  deformer_.reset();  // it refers to the planner
  api_->destroy(planner_);
}

PectusPlannerBasisSummary PlannerClient::BuildBasis(const PectusPlannerBasisOptions* options) {
  deformer_.reset();  // a rebuild needs the old basis' deformers gone
  PectusPlannerBasisSummary summary{};
  PectusPlannerStatus status{};
  ThrowIfFailed(api_->build_basis(planner_, options, &summary, &status), status);
  PectusPlannerDeformer* deformer = nullptr;
  ThrowIfFailed(api_->create_deformer(planner_, &deformer, &status), status);
  deformer_ = std::unique_ptr<PectusPlannerDeformer, DeformerDeleter>(deformer, DeformerDeleter{api_});
  return summary;
}

PectusPlannerBasisSummary PlannerClient::LoadBasis(const std::filesystem::path& dataset) {
  deformer_.reset();
  PectusPlannerBasisSummary summary{};
  PectusPlannerStatus status{};
  ThrowIfFailed(api_->load_basis(planner_, dataset.c_str(), &summary, &status), status);
  PectusPlannerDeformer* deformer = nullptr;
  ThrowIfFailed(api_->create_deformer(planner_, &deformer, &status), status);
  deformer_ = std::unique_ptr<PectusPlannerDeformer, DeformerDeleter>(deformer, DeformerDeleter{api_});
  return summary;
}

std::vector<PlannedCase> PlannerClient::Deform(const std::vector<BarPlacement>& bars, bool with_bone) const {
  if (!deformer_) ThrowUsage("planner: no response basis; BuildBasis() first");
  const Eigen::Index nb = bone_.num_vertices(), ns = skin_.num_vertices();
  const auto nl = static_cast<Eigen::Index>(skin_landmarks_.size());
  std::vector<PlannedCase> out(bars.size());
  Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor> marks(nl, 3);
  for (std::size_t k = 0; k < bars.size(); ++k) {
    PlannedCase& c = out[k];
    c.bar = bars[k];
    if (with_bone) c.bone.resize(nb, 3);
    c.skin.resize(ns, 3);
    const PectusPlannerBar bar = ToBar(bars[k]);
    PectusPlannerStatus status{};
    ThrowIfFailed(api_->deform(deformer_.get(), &bar, with_bone ? c.bone.data() : nullptr, c.skin.data(),
                               marks.data(), &c.figures.sternum_lift_mm, &status),
                  status);
    for (Eigen::Index i = 0; i < nl; ++i) {
      c.skin_landmarks.items.push_back({skin_landmarks_.items[static_cast<std::size_t>(i)].label,
                                        marks.row(i).transpose(), "on the predicted skin"});
    }
  }
  return out;
}

Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> PlannerClient::BasisModes() const {
  if (!deformer_) ThrowUsage("planner: no response basis; BuildBasis() first");
  PectusPlannerStatus status{};
  std::int64_t rows = 0, rank = 0;
  ThrowIfFailed(api_->basis_modes(planner_, nullptr, 0, &rows, &rank, &status), status);
  Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> modes(rows, rank);
  ThrowIfFailed(api_->basis_modes(planner_, modes.data(), modes.size(), &rows, &rank, &status), status);
  return modes;
}

bool PlannerClient::BasisCoefficients(const BarPlacement& bar, Eigen::VectorXd* coefficients,
                                      double* lift_per_n) const {
  if (!deformer_) ThrowUsage("planner: no response basis; BuildBasis() first");
  std::int64_t rank = 0;
  PectusPlannerStatus status{};
  ThrowIfFailed(api_->basis_modes(planner_, nullptr, 0, nullptr, &rank, &status), status);
  coefficients->resize(rank);
  const PectusPlannerBar b = ToBar(bar);
  return api_->basis_coefficients(deformer_.get(), &b, coefficients->data(), lift_per_n, &status) ==
         PECTUS_PLANNER_OK;
}

LandmarkSet PlannerClient::Landmarks(int which) const {
  PectusPlannerStatus status{};
  std::int32_t count = 0;
  ThrowIfFailed(api_->landmarks(planner_, which, nullptr, 0, &count, &status), status);
  std::vector<PectusPlannerLandmark> items(static_cast<std::size_t>(count));
  ThrowIfFailed(api_->landmarks(planner_, which, items.data(), count, &count, &status), status);
  static const char* kWhere[] = {"on the ribcage", "on the skin", "on the skin without the deformity"};
  LandmarkSet set;
  for (const auto& l : items) {
    set.items.push_back(
        {l.label, Eigen::Vector3d(l.position[0], l.position[1], l.position[2]), kWhere[which]});
  }
  return set;
}

std::vector<PlannedCase> PlannerClient::Solve(const std::vector<BarPlacement>& bars, bool with_bone) const {
  std::vector<PectusPlannerBar> c_bars;
  for (const BarPlacement& b : bars) c_bars.push_back(ToBar(b));
  const auto n = static_cast<Eigen::Index>(bars.size());
  const Eigen::Index nb = bone_.num_vertices(), ns = skin_.num_vertices();
  const auto nl = static_cast<Eigen::Index>(skin_landmarks_.size());
  std::vector<double> bone(with_bone ? static_cast<std::size_t>(n * nb * 3) : 0);
  std::vector<double> skin(static_cast<std::size_t>(n * ns * 3)), marks(static_cast<std::size_t>(n * nl * 3));
  std::vector<PectusPlannerCaseResult> figures(bars.size());
  PectusPlannerStatus status{};
  ThrowIfFailed(api_->solve(planner_, c_bars.data(), n, with_bone ? bone.data() : nullptr, skin.data(),
                            marks.data(), figures.data(), &status),
                status);
  std::vector<PlannedCase> out(bars.size());
  for (Eigen::Index k = 0; k < n; ++k) {
    PlannedCase& c = out[static_cast<std::size_t>(k)];
    c.bar = bars[static_cast<std::size_t>(k)];
    if (with_bone) c.bone = Eigen::Map<const Points3>(bone.data() + k * nb * 3, nb, 3);
    c.skin = Eigen::Map<const Points3>(skin.data() + k * ns * 3, ns, 3);
    for (Eigen::Index i = 0; i < nl; ++i) {
      c.skin_landmarks.items.push_back({skin_landmarks_.items[static_cast<std::size_t>(i)].label,
                                        Eigen::Map<const Eigen::Vector3d>(marks.data() + (k * nl + i) * 3),
                                        "on the predicted skin"});
    }
    c.figures = figures[static_cast<std::size_t>(k)];
  }
  return out;
}

std::vector<PectusPlannerForceToLift> PlannerClient::ForceToLift(
    const std::vector<BarPlacement>& positions) const {
  std::vector<PectusPlannerBar> c_bars;
  for (const BarPlacement& b : positions) c_bars.push_back(ToBar(b));
  std::vector<PectusPlannerForceToLift> out(positions.size());
  PectusPlannerStatus status{};
  ThrowIfFailed(api_->force_to_lift(planner_, c_bars.data(), static_cast<std::int64_t>(c_bars.size()),
                                    out.data(), &status),
                status);
  return out;
}

PectusPlannerPatient ReadPlannerPatient(const PlannerPlugin& plugin, const std::filesystem::path& table,
                                        const std::string& patient) {
  PectusPlannerPatient out{};
  PectusPlannerStatus status{};
  ThrowIfFailed(plugin.api().read_patient(table.c_str(), patient.c_str(), &out, &status), status);
  return out;
}

PectusPlannerOptions PluginDefaultOptions(const PlannerPlugin& plugin) {
  PectusPlannerOptions options{};
  plugin.api().default_options(&options);
  return options;
}

namespace {

// A progress callback across the C boundary: it must not throw.
void ProgressTrampoline(void* user, std::int64_t done, std::int64_t total) {
  const auto* f = static_cast<const std::function<void(std::int64_t, std::int64_t)>*>(user);
  try {
    if (*f) (*f)(done, total);
  } catch (...) {
  }
}

void* ProgressUser(const std::function<void(std::int64_t, std::int64_t)>& progress) {
  return const_cast<std::function<void(std::int64_t, std::int64_t)>*>(&progress);
}

}  // namespace

PectusPlannerDatasetSummary WritePlannerDataset(
    const PlannerPlugin& plugin, const std::filesystem::path& table, const std::filesystem::path& output,
    const PectusPlannerOptions& options, const std::function<void(std::int64_t, std::int64_t)>& progress,
    const PectusPlannerBasisOptions* basis) {
  PectusPlannerDatasetSummary summary{};
  PectusPlannerStatus status{};
  ThrowIfFailed(plugin.api().write_dataset(table.c_str(), output.c_str(), &options, basis, ProgressTrampoline,
                                           ProgressUser(progress), &summary, &status),
                status);
  return summary;
}

EmulatorEvaluationReport EvaluatePlannerEmulator(
    const PlannerPlugin& plugin, const std::filesystem::path& table, const std::string& patients,
    const PectusPlannerOptions& options, const PectusPlannerEmulatorOptions& emulator,
    const std::function<void(std::int64_t, std::int64_t)>& progress) {
  EmulatorEvaluationReport report;
  report.patients.resize(ReadPatientTable(table).size());  // at most every row of the table
  PectusPlannerStatus status{};
  ThrowIfFailed(plugin.api().evaluate_emulator(
                    table.c_str(), patients.empty() ? nullptr : patients.c_str(), &options, &emulator,
                    ProgressTrampoline, ProgressUser(progress), &report.summary, report.patients.data(),
                    static_cast<std::int64_t>(report.patients.size()), &status),
                status);
  report.patients.resize(static_cast<std::size_t>(
      std::min<std::int64_t>(report.summary.patients, static_cast<std::int64_t>(report.patients.size()))));
  return report;
}

}  // namespace pectus::planner
