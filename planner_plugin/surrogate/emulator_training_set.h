// pectus planner: the training data of the response emulator (issue 14). Per patient of a table, the
// finite element model (the fitted ribcage, factorised once) solved with a 1 N bar at a few positions along
// the sternum: the displacement per newton of every skin grid vertex (and, if asked, of every bone-surface
// vertex) and the sternal lift per newton. The model is linear, so a load case (position s, force F) is
// F times the response at s. Across patients, skin vertex (row, column) is the same grid point (the same
// fraction of the way from above the notch to below the xiphoid, the same angle about the chest's axis);
// bone-surface vertex i is the same node of the generic ribcage. The set also records, per skin vertex,
// where its ties sit on the generic ribcage (EmulatorTrainingSet::skin_anchor_generic_mm), so that a user
// can check that the grid vertex is the same anatomical point in every patient before relying on it.
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "planner_plugin/plugin/planner_session.h"
#include "shape/core/timings.h"

namespace pectus::planner {

/// What the training set holds and how it is built.
struct EmulatorTrainingSetOptions {
  /// Bar positions, fractions of the sternal length from the notch (each in (0, 1)). Default: the
  /// dissertation's three (DissertationLoadCases()).
  std::vector<double> positions = {0.65, 0.75, 0.85};
  /// Also keep the bone-surface vertices' responses (MakeBoneSurface; about 3x the skin's size). Default
  /// false.
  bool bone_surface = false;
  /// Also keep the responses of every boundary node of the mesh (corner and mid-edge: the nodes the skin
  /// is tied to, the same nodes in every patient) and each patient's skin ties to them, so that a
  /// prediction of the nodes gives the skin through the patient's own ties. Default true.
  bool boundary_nodes = true;
  /// Mesh, fit, materials and skin settings (the plugin's defaults).
  PlannerSettings settings;
  /// False, with the reason, for a position out of (0, 1) or invalid settings.
  bool IsValid(std::string* why) const;
};

/// The responses of n patients at q bar positions. Displacements are per newton of bar force (mm/N),
/// stored per patient as one row: vertex after vertex, x, y, z (LPS, the patient's notch frame).
struct EmulatorTrainingSet {
  std::vector<std::string> patients;  ///< n patient ids (the table's patient numbers)
  Eigen::VectorXd positions;          ///< q bar positions, fractions of the sternal length
  /// n by 6 CT measurements in true size: width, depth, sternal length, depression (mm, divided by the
  /// magnification), torsion (degrees), the CT's Haller index (0 if unknown). Names: kCtInputNames.
  Eigen::MatrixXd ct_inputs;
  /// n by 8 measurements of the fitted model (for more inputs): the patient map's scale x, y, z, its
  /// sternal depression (mm) and torsion (degrees), the spine shift (mm), the model's inner width and
  /// sternum-to-spine distance (mm). Names: kModelInputNames.
  Eigen::MatrixXd model_inputs;
  Eigen::MatrixXd lift_per_newton;  ///< n by q sternal lift per newton, mm/N
  int skin_rows = 0, skin_columns = 0;
  /// Per position, n by 3 #skin vertices (skin_rows x skin_columns, row-major), mm/N.
  std::vector<Eigen::MatrixXd> skin;
  /// Per position, n by 3 #bone-surface vertices, mm/N (empty when not asked for).
  std::vector<Eigen::MatrixXd> bone;
  /// The mesh's boundary nodes (ExtractBoundary(); the same in every patient), empty when not asked for.
  std::vector<std::int32_t> boundary_nodes;
  /// Per position, n by 3 #boundary nodes, mm/N (empty when not asked for).
  std::vector<Eigen::MatrixXd> boundary;
  /// Per patient, #skin vertices by #boundary nodes: the skin's ties (SkinSurface::ties; rows sum to 1), so
  /// that a skin vertex's displacement is its row times the boundary nodes' (x, y, z each). Empty when not
  /// asked for.
  std::vector<Eigen::SparseMatrix<double, Eigen::RowMajor>> skin_ties;
  /// Per patient, 1 by 3 #boundary nodes: the sternal lift as a linear functional of the boundary nodes'
  /// displacements (RibcageFem::SternumLiftTies(), on the y coordinates), known from the fitted ribcage
  /// alone: lift = this row times a boundary response. Empty when not asked for.
  std::vector<Eigen::SparseMatrix<double, Eigen::RowMajor>> lift_ties;
  /// n by 3 #skin vertices: the skin vertex's ties evaluated on the generic ribcage's nodes (mm): the
  /// same anatomical point in every patient iff these agree across patients.
  Eigen::MatrixXd skin_anchor_generic_mm;
  Timings timings_s;  ///< "fit" (the ribcages), "fem" (assembly, factorisation, solves), "skin"

  Eigen::Index num_patients() const { return static_cast<Eigen::Index>(patients.size()); }
  Eigen::Index num_positions() const { return positions.size(); }
  Eigen::Index num_skin_vertices() const { return static_cast<Eigen::Index>(skin_rows) * skin_columns; }
  /// Throws Error(kBadInput) naming `what` if the shapes disagree with each other.
  void CheckShapes(const std::string& what) const;
};

/// Column names of EmulatorTrainingSet::ct_inputs and ::model_inputs.
extern const std::vector<std::string> kCtInputNames;
extern const std::vector<std::string> kModelInputNames;

/// Builds the training set from every row of `rows` (one generic ribcage, one factorisation per patient).
/// `progress(done, total)` is called after each patient. Throws Error(kUsage) for invalid options and
/// pectus::Error naming the patient whose ribcage cannot be fitted or solved.
EmulatorTrainingSet BuildEmulatorTrainingSet(
    const std::vector<PatientTableRow>& rows, const EmulatorTrainingSetOptions& options = {},
    const std::function<void(std::int64_t, std::int64_t)>& progress = {});

/// Writes `set` to `path` as a little-endian binary file: the 16-byte magic "pectus-emulator3", then the
/// counts (int64: n, q, p_ct, p_model, skin rows, skin columns, bone vertices, boundary nodes), the patient
/// ids (int64 length + bytes each), then float64 arrays in order: positions, ct_inputs, model_inputs,
/// lift_per_newton (row-major), the skin per position, the bone per position, skin_anchor_generic_mm
/// (row-major); then, with boundary nodes, the boundary nodes (int64 each), the boundary per position
/// (float64, row-major), per patient the skin ties (int64 count of entries, then per entry int64 skin
/// vertex, int64 boundary index, float64 weight) and per patient the lift ties (int64 count, then per entry
/// int64 coordinate index, float64 weight); and last an int64 count of every float64 written (a truncated
/// file fails). Throws Error(kFailure) naming the file.
void SaveEmulatorTrainingSet(const EmulatorTrainingSet& set, const std::filesystem::path& path);

/// Reads a file written by SaveEmulatorTrainingSet. Throws Error(kBadInput) naming the file if it is
/// missing, of another format, truncated or inconsistent.
EmulatorTrainingSet LoadEmulatorTrainingSet(const std::filesystem::path& path);

}  // namespace pectus::planner
