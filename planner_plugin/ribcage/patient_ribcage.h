// pectus planner: a patient's ribcage from CT measurements (dissertation §4.1.1, Figure 24): the
// generic ribcage scaled non-uniformly to the patient's width, depth and sternal length, and its
// sternum depressed and twisted by skinning, with the five parameters fitted so that measuring the
// result gives back the patient's measurements.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "planner_plugin/fem/tet_mesh.h"
#include "planner_plugin/ribcage/build_generic_ribcage.h"
#include "planner_plugin/ribcage/ribcage_measurements.h"
#include "planner_plugin/ribcage/sternum_skinning.h"
#include "shape/core/landmarks.h"
#include "shape/io/patient_table_io.h"

namespace pectus::planner {

/// A patient's measurements, as taken on the CT (Figure 24 of the dissertation). Lengths in mm.
struct PatientMeasurements {
  std::string patient;  ///< identifier, for messages (e.g. "57")
  /// Magnification of the CT images: lengths measured in the image plane (width, depth, depression)
  /// are divided by it. Must be given, even when 1 (as the dissertation's ribcage modeller insists).
  double magnification = 1.0;
  double width_mm = 0;  ///< ribcage width on the slice of deepest depression (image), 100-500
  double depth_mm = 0;  ///< ribcage depth on the same slice (image), 60-400
  /// Sternal length, mm (40-400); or, when slice_spacing_mm > 0, computed as
  /// (last_sternum_slice - first_sternum_slice) * slice_spacing_mm.
  double sternal_length_mm = 0;
  double first_sternum_slice = 0, last_sternum_slice = 0, slice_spacing_mm = 0;
  double depression_mm = 0;  ///< sternal depression on the image, 0 to 60
  double torsion_deg = 0;    ///< sternal torsion, -45 to 45 (positive: the right edge deeper)
  /// The CT's Haller index (inner width / sternum to spine on the slice of deepest depression), 1 to
  /// 50; 0 if unknown. Given, the spine's anterior surface is placed to give it back (the other five
  /// measurements do not see the spine); unknown, the generic ribcage's spine is kept.
  double haller_index = 0;

  /// False, with the reason (naming the patient), if a value is out of range.
  bool IsValid(std::string* why) const;
  /// The targets in true millimetres: width, depth, depression divided by the magnification.
  double TrueWidth() const { return width_mm / magnification; }
  double TrueDepth() const { return depth_mm / magnification; }
  double TrueDepression() const { return depression_mm / magnification; }
  double SternalLength() const;
};

/// Copies the six CT measurements that a patient table row (PatientTableRow), the plugin's C patient
/// (PectusPlannerPatient) and PatientMeasurements name alike, from `from` to `to`: the magnification,
/// the width, depth, sternal length and depression (image mm) and the torsion (degrees).
template <class From, class To>
void CopyCtMeasurements(const From& from, To* to) {
  to->magnification = from.magnification;
  to->width_mm = from.width_mm;
  to->depth_mm = from.depth_mm;
  to->sternal_length_mm = from.sternal_length_mm;
  to->depression_mm = from.depression_mm;
  to->torsion_deg = from.torsion_deg;
}

/// The measurements of a row of the patient table (read by pectus::ReadPatientTable, which has already
/// checked the same ranges as PatientMeasurements::IsValid), named by the patient's number.
PatientMeasurements MeasurementsOf(const PatientTableRow& row);

/// Options of the patient fit.
struct PatientRibcageOptions {
  SternumSkinningOptions skinning;
  RibcageMeasurementOptions measurement;
  /// The fit stops when every length is within this of its target, mm (angles: this many degrees).
  /// Default 0.01. Where the slice of deepest depression hops between two nearly equally deep levels
  /// the fit may not get this close; it then returns its best iterate (residual_mm says how close:
  /// a few tenths of a millimetre for the dissertation's patients).
  double tolerance_mm = 0.01;
  int max_iterations = 30;  ///< default 30
  bool IsValid(std::string* why) const;
};

/// The five parameters of the patient map.
struct PatientMapParameters {
  Eigen::Vector3d scale = Eigen::Vector3d::Ones();  ///< non-uniform scale about the notch (x, y, z)
  double depression_mm = 0;                         ///< posterior translation of the sternal bone
  double torsion_rad = 0;                           ///< rotation of the sternal bone about its axis
};

/// A patient's ribcage, ready for finite elements.
struct PatientRibcage {
  std::string patient;
  TetMesh mesh;                           ///< quadratic tetrahedra; regions: RibcageRegion
  Eigen::Index num_corner_nodes = 0;      ///< mesh.nodes' first rows are the corner nodes
  Eigen::VectorXi tet_parts;              ///< as GenericRibcage::tet_parts
  std::vector<std::int32_t> fixed_nodes;  ///< every node (corner and mid-edge) on the posterior rib ends
  Tri6Connectivity
      sternum_posterior_faces;  ///< boundary faces on the sternum's posterior surface (bar contact)
  std::vector<std::int32_t> sternum_anterior_midline;  ///< corner nodes, notch first
  LandmarkSet
      landmarks;  ///< sternal_notch, manubrium_centre, sternal_angle, xiphoid (joint), xiphoid_tip (mm)
  RibcageSurface surface;           ///< the corner-node bone surface with parts and spine, for measurements
  PatientMapParameters parameters;  ///< the fitted map
  /// How far the spine's anterior surface was moved along y (mm, + posterior) from the scaled generic
  /// one to give back targets.haller_index (0 when it is unknown).
  double spine_shift_mm = 0;
  PatientMeasurements targets;   ///< what was asked for
  RibcageMeasurements measured;  ///< what the generated ribcage measures
  bool converged = false;        ///< every residual within options.tolerance_mm
  double residual_mm = 0;        ///< the largest residual of the returned map (mm, or degrees for torsion)
  int iterations = 0;
  std::string message;  ///< one line: converged or not, residuals
};

/// Maps the generic ribcage's corner nodes (#nodes by 3) by `parameters`: scale, then skinning.
Points3 MapGenericNodes(const GenericRibcage& generic, const PatientMapParameters& parameters,
                        const SternumSkinningOptions& skinning);

/// The skinning of the generic ribcage scaled by `scale` (the weights of the patient map).
SternumSkinning MakeSternumSkinning(const GenericRibcage& generic, const Eigen::Vector3d& scale,
                                    const SternumSkinningOptions& skinning);

/// Fits the patient map to `targets` and builds the patient's quadratic mesh. Throws Error(kBadInput)
/// naming the patient for invalid measurements or a fitted ribcage that folds an element, and
/// Error(kUsage) for a generic ribcage of fewer than 10 rib pairs (the CT's slice of deepest depression
/// crosses the costal margin, ribs 8-10). A fit that does not reach the tolerance is returned
/// with converged = false and the residuals in `message` (the caller decides).
PatientRibcage MakePatientRibcage(const GenericRibcage& generic, const PatientMeasurements& targets,
                                  const PatientRibcageOptions& options = {});

}  // namespace pectus::planner
