// pectus planner: the finite element dataset (dissertation §4.1.2: 62 patients x 24 load cases = 1488
// results) written as one HDF5 file. Layout, all lengths in mm, forces in N, frame LPS with the origin
// at each patient's sternal notch (docs in the file's attributes too):
//   /                      attrs: description, units, frame, load_case_order
//   /load_cases/position   (24) bar position, fraction of the sternal length from the notch
//   /load_cases/force_n    (24) bar force, N
//   /topology/faces        (#faces x 3) int32, triangles of the bone surface over the surface nodes
//   /topology/face_region  (#faces) int32: 0 sternum, 1 rib, 2 costal cartilage
//   /topology/face_part    (#faces) int32: 0 sternum, k left rib k, -k right rib k
//   /patients/<id>/        attrs: CT width, depth, sternal length, depression, Haller index; the same
//                          measured on the model; the fitted map; force to lift per bar position
//   /patients/<id>/nodes          (#surface nodes x 3) float64, undeformed positions
//   /patients/<id>/displacements  (24 x #surface nodes x 3) float32, one slab per load case
//   /patients/<id>/sternum_lift   (24) float64, anterior lift of the sternum at the deepest level
//   /patients/<id>/response_basis/  (optional; `pectus surrogate build`) the patient's exact response basis
//                          (BarResponseBasis::Stored): modes (3P x r) float32, mixing (r x J), lift (J),
//                          contact_nodes (J) int32, quadrature_z, quadrature_weight (Q), quadrature_contact
//                          (Q x 6) int32, quadrature_N (Q x 6), singular_values, and scalars (10 float64):
//                          num_points, contact_width_mm, notch_z_mm, sternal_length_mm,
//                          truncation_bound_mm_per_n, then the points it answers for: bone_vertices,
//                          skin_vertices, skin_landmarks (in that order), mesh_nodes and rest_checksum_mm of
//                          the planner it was built in (the order is also the group's attribute)
// The surface nodes are the corner nodes of the quadratic mesh that lie on its boundary; the topology
// is the same for every patient (the generic mesh mapped), so a node index means the same anatomical
// point in every patient.
#pragma once

#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "planner_plugin/ribcage/bar_response_basis.h"
#include "planner_plugin/ribcage/build_generic_ribcage.h"
#include "planner_plugin/ribcage/ribcage_fem.h"
#include "shape/core/atomic_file.h"
#include "shape/core/geometry.h"

namespace pectus::planner {

/// A patient's exact response basis as the FE dataset keeps it: the arrays, and which output points they
/// answer for (a planner's bone surface vertices, skin vertices and skin landmarks, in that order).
struct StoredResponseBasis {
  BarResponseBasis::Stored arrays;
  std::int64_t bone_vertices = 0, skin_vertices = 0, skin_landmarks = 0;
  std::int64_t mesh_nodes = 0;  ///< of the mesh it was built on
  double rest_checksum_mm =
      0.0;  ///< RestChecksum() of the points' rest positions: another mesh or skin differs
};

/// A fingerprint of rest positions (3 #points, row-major): sum of x_i (1 + i mod 7), mm.
double RestChecksum(const Eigen::VectorXd& rest_positions);

/// The FE dataset as read back (layout above): the load cases, the shared topology, every patient.
struct FemDataset {
  /// One patient's arrays.
  struct Patient {
    std::string id;                            ///< the group name under /patients
    Points3 nodes_mm;                          ///< #surface nodes by 3, undeformed positions
    std::vector<Points3> displacements_mm;     ///< one #surface nodes by 3 block per load case
    Eigen::VectorXd sternum_lift_mm;           ///< one per load case
    std::optional<StoredResponseBasis> basis;  ///< if the dataset was written with bases
  };
  Eigen::VectorXd position;     ///< #cases, bar position as a fraction of the sternal length (0-1)
  Eigen::VectorXd force_n;      ///< #cases, bar force, N
  Faces3 faces;                 ///< triangles over the surface nodes
  Eigen::VectorXi face_region;  ///< per face: 0 sternum, 1 rib, 2 costal cartilage
  Eigen::VectorXi face_part;    ///< per face: 0 sternum, k left rib k, -k right rib k
  std::vector<Patient> patients;
};

/// Reads an FE dataset written by FemDatasetWriter. Throws Error(kBadInput) naming the file and the
/// dataset for anything missing, of the wrong shape, non-finite or out of range (a face index beyond
/// the surface nodes, a region other than 0-2, a position outside 0-1).
FemDataset ReadFemDataset(const std::filesystem::path& path);

/// ReadFemDataset from a file held in memory (an HDF5 file image); `name` is the file named in errors.
FemDataset ParseFemDataset(std::string_view bytes, const std::string& name);

/// Only patient `patient`'s response basis from an FE dataset file (without reading the rest). Throws
/// Error(kBadInput) naming the file if it has no such patient or no basis for it, or the basis is broken.
StoredResponseBasis ReadStoredResponseBasis(const std::filesystem::path& path, const std::string& patient);

/// What AssembleFemDataset joined.
struct FemDatasetAssembly {
  std::vector<std::string> patients;  ///< the parts' patients, in order
  std::int64_t load_cases = 0, surface_nodes = 0;
};

/// Assembles an FE dataset from parts: one-patient datasets written by FemDatasetWriter (a task farm's
/// results, one per patient). The first part's attributes, load cases and topology, then every part's
/// patient group in the order of `parts`, copied as stored (H5Ocopy: no recompression). The file has no
/// object times and a fixed format version, so the same parts give the same bytes. Nothing appears at
/// `path` unless it is complete. Throws Error(kBadInput) naming the
/// part at fault: not a dataset, not one patient, a patient twice, load cases or topology unlike the
/// first part's (made with other options).
FemDatasetAssembly AssembleFemDataset(const std::vector<std::filesystem::path>& parts,
                                      const std::filesystem::path& path);

/// Writes the dataset patient by patient; nothing is visible at `path` until Commit().
class FemDatasetWriter {
 public:
  /// @param[in] path     the .h5 file to write (replaced on Commit)
  /// @param[in] generic  the generic ribcage every patient is made from (defines the surface topology)
  /// @param[in] loads    the load cases, the same for every patient (positions as fractions)
  /// Throws Error(kFailure) naming the file if HDF5 cannot create it.
  FemDatasetWriter(const std::filesystem::path& path, const GenericRibcage& generic,
                   std::vector<BarLoad> loads, const RibcageMaterials& materials = {});
  ~FemDatasetWriter();
  FemDatasetWriter(const FemDatasetWriter&) = delete;
  FemDatasetWriter& operator=(const FemDatasetWriter&) = delete;

  /// Adds one patient: `results` in the order of the constructor's `loads`; `force_to_lift` per
  /// position; `ct_haller_index` from the patient table (0 if unknown).
  void AddPatient(const PatientRibcage& ribcage, const std::vector<BarResult>& results,
                  const std::vector<ForceToLift>& force_to_lift, double ct_haller_index,
                  const StoredResponseBasis* basis = nullptr);
  /// Closes the file and moves it into place.
  void Commit();
  /// Number of surface nodes per patient.
  Eigen::Index num_surface_nodes() const { return static_cast<Eigen::Index>(surface_nodes_.size()); }

 private:
  struct File;
  OutputTransaction output_;    // the staged file; removed if never committed
  std::unique_ptr<File> file_;  // the open HDF5 file (closed before output_ commits or removes it)
  std::filesystem::path path_, temp_;
  std::vector<BarLoad> loads_;
  std::vector<std::int32_t> surface_nodes_;
};

}  // namespace pectus::planner
