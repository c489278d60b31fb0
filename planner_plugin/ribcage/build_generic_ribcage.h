// pectus planner: the generic ribcage, built procedurally with anatomical proportions and meshed as
// swept hexahedral blocks split into tetrahedra (dissertation §4.1.1, Figure 17).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "planner_plugin/fem/tet_mesh.h"
#include "planner_plugin/ribcage/chest_shell.h"
#include "shape/core/geometry.h"

namespace pectus::planner {

/// Material regions of the ribcage mesh (indices into a material list: sternum, rib, cartilage).
enum RibcageRegion : int { kSternumRegion = 0, kRibRegion = 1, kCartilageRegion = 2 };

/// Proportions and mesh resolution of the generic ribcage. The default anatomy is that of the
/// dissertation's 62 patients on average (width 252 mm, depth 142 mm, sternal length 153 mm) without
/// depression; a patient's ribcage is this one scaled and deformed (patient_ribcage.h).
struct GenericRibcageOptions {
  /// Rib pairs: ribs 1-7 join the sternum through their costal cartilages; ribs 8-10 join the
  /// cartilage above (the costal margin). 7 to 10. Default 10.
  int rib_pairs = 10;
  /// Forward lean of the sternum from vertical, degrees (its lower end is anterior). Default 20.
  double sternum_tilt_deg = 20.0;
  /// Sternal length of the generic model, mm: the height (z extent) from the notch to the xiphoid
  /// tip, as measured on axial CT slices. Default 153.
  double sternal_length_mm = 153.0;
  /// Cells along the sternum (its arc), across its width and through its thickness. Defaults 34, 4, 2.
  /// Each costal cartilage joins the sternum over rib_cells_height cells along it.
  int sternum_cells_along = 34;
  int sternum_cells_across = 4;
  int sternum_cells_through = 2;
  /// Cells across the height and through the thickness of a rib or cartilage. Defaults 2, 2: with
  /// quadratic tetrahedra, two cells across a beam bend within about 1 % of beam theory.
  int rib_cells_height = 2;
  int rib_cells_thickness = 2;
  /// Target length of a cell along a rib, mm. Default 6. Costal cartilages take it clamped to 4 mm ..
  /// 12 mm / rib_cells_height (6 mm by default): their joints fold otherwise. Every value from 2 to 20 mm
  /// builds (tested).
  double rib_cell_length_mm = 6.0;
  /// How far the anterior surface of the vertebral bodies lies in front of the rib heads, mm (sets the
  /// spine line used by the Haller index). Default 20.
  double vertebral_body_offset_mm = 20.0;

  /// False, with the reason in `why`, if a value is out of range (counts must be even where a
  /// midline node is needed: sternum_cells_across and sternum_cells_through).
  bool IsValid(std::string* why) const;
};

/// Named anatomical points of the ribcage, each a node on the sternum's anterior midline.
struct RibcageLandmarkNodes {
  std::int32_t sternal_notch = -1;             ///< top of the manubrium (the origin of the generic frame)
  std::int32_t manubriosternal_junction = -1;  ///< the sternal angle (Louis), level of rib 2
  std::int32_t xiphisternal_junction = -1;     ///< lower end of the sternal body
  std::int32_t xiphoid_tip = -1;               ///< lower end of the xiphoid process
};

/// The generic ribcage: a linear tetrahedral mesh (corner nodes only; it is lifted to quadratic after
/// the patient mapping) with the tags the planner needs. Frame: LPS, mm, origin at the sternal notch
/// (see ChestShell).
struct GenericRibcage {
  Points3 nodes;              ///< #corner nodes by 3, mm
  Tet4Connectivity tets;      ///< #tets by 4, positively oriented
  Eigen::VectorXi regions;    ///< #tets RibcageRegion
  Eigen::VectorXi tet_parts;  ///< #tets: 0 sternum, k left rib k (with its cartilage), -k right rib k
  std::vector<std::int32_t> fixed_nodes;               ///< the posterior rib ends (rib heads at the spine)
  std::vector<std::int32_t> sternum_posterior_nodes;   ///< nodes of the sternum's posterior surface
  std::vector<std::int32_t> sternum_anterior_midline;  ///< anterior midline nodes, notch to xiphoid tip
  std::vector<std::int32_t> sternum_axis;  ///< centre of the sternum's section at each station, notch first
  std::vector<double> sternum_half_width;  ///< half-width of the sternum at each station, mm
  RibcageLandmarkNodes landmarks;
  Points3 spine_anterior;  ///< polyline of the anterior surface of the vertebral bodies (midline), top first
  ChestShell shell;        ///< the surface the rib centre lines lie on
  double sternal_arc_length_mm = 0;  ///< length of the sternum along its axis
  std::vector<double>
      rib_attachment_fraction;    ///< per rib 1-7: centre of its sternal joint, fraction of the arc
  GenericRibcageOptions options;  ///< what it was built with
};

/// Builds the generic ribcage. Throws Error(kUsage) for invalid options and Error(kFailure) if the
/// construction tangles an element (a bug or extreme options).
GenericRibcage BuildGenericRibcage(const GenericRibcageOptions& options = {});

}  // namespace pectus::planner
