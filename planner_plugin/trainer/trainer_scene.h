// pectus trainer: the scene of the Nuss trainer (dissertation §4.4) built from a patient's ribcage: the
// bones (sternum, ribs and costal cartilages) from the CT-fitted ribcage, the pericardium (heart) and the
// lungs as closed meshes placed from the same measurements, the intercostal spaces, and the planned
// tunnel of the introducer (entry through the right space, under the sternum above the pericardium, exit
// through the matching left space). Placement rules: docs/trainer.md.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "planner_plugin/ribcage/patient_ribcage.h"
#include "planner_plugin/trainer/triangle_grid.h"
#include "shape/core/geometry.h"

namespace pectus::trainer {

/// What a collision triangle belongs to (its tissue, hence its stiffness).
enum Organ : int { kBone = 0, kPericardium = 1, kLung = 2, kNumOrgans = 3 };

/// A gap between two consecutive ribs: the n-th intercostal space lies between rib n and rib n + 1.
struct IntercostalSpace {
  int side = 0;    ///< -1 right (x < 0 in LPS), +1 left; 0: not in a space
  int number = 0;  ///< 1-9; 0: not in a space
  bool operator==(const IntercostalSpace& o) const { return side == o.side && number == o.number; }
  /// "right 4", "left 5" or "none".
  std::string Name() const;
};

/// The planned pathway of the introducer's tip.
struct PlannedTunnel {
  Points3 points;                ///< #samples by 3, right port first, about 2 mm apart
  Eigen::Vector3d entry_port;    ///< centre of the right intercostal space it enters through, mm
  Eigen::Vector3d exit_port;     ///< centre of the left space it leaves through, mm
  IntercostalSpace entry, exit;  ///< the planned spaces
  double level_z_mm = 0;         ///< height of the bar's level (the slice of deepest depression)
  double length_mm = 0;          ///< polyline length
};

/// An ellipsoid organ: its closed mesh and how it was placed.
struct OrganPlacement {
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();     ///< mm
  Eigen::Vector3d semi_axes = Eigen::Vector3d::Zero();  ///< along x, y, z, mm
  TriangleMesh mesh;                                    ///< closed, outward
};

/// Placement rules (docs/trainer.md, "Scene"). Lengths in mm.
struct TrainerSceneOptions {
  /// Anterior mediastinum: the pericardium's nearest approach to any bone (sternum, cartilage, rib),
  /// mm. Default 12: the tunnel then passes 6 mm from it, 2 mm clear of the medium introducer's shaft.
  double mediastinal_gap_mm = 12.0;
  /// The pericardium's centre lies this far left of the midline in a chest without depression, mm
  /// (default 15), plus `heart_shift_per_depression` times the sternal depression (default 1.0).
  double heart_shift_mm = 15.0;
  double heart_shift_per_depression = 1.0;
  /// The pericardium's semi-axes as fractions of the ribcage's width (x), depth (y) and the sternal
  /// length (z). Defaults 0.22, 0.30, 0.36.
  Eigen::Vector3d heart_fractions = Eigen::Vector3d(0.22, 0.30, 0.36);
  /// The pericardium's centre, this fraction of the sternal length below the notch. Default 0.75.
  double heart_level = 0.75;
  /// The lungs keep this far from every bone (retracted from the anterior chest wall by the capnothorax
  /// of thoracoscopy) and 2 mm from the pericardium, mm. Default 15.
  double pleural_gap_mm = 15.0;
  /// Azimuth of the ports from the anterior midline about the chest's axis, degrees. Default 60.
  double port_azimuth_deg = 60.0;
  /// The tunnel runs this far inside the rib band's centre behind each port, mm. Default 12.
  double port_inset_mm = 12.0;
  /// Icosphere subdivisions of the organ meshes (3: 1280 triangles, 4: 5120). Default 4.
  int organ_subdivisions = 4;
  /// Cell of the collision grid, mm. Default 6.
  double grid_cell_mm = 6.0;
  bool IsValid(std::string* why) const;
};

/// The trainer's scene. Frame: the ribcage's (LPS, mm, origin at the sternal notch).
struct TrainerScene {
  std::string patient;
  Points3 bone_vertices;       ///< the bone surface: #vertices by 3
  Faces3 bone_faces;           ///< #faces by 3, outward
  Eigen::VectorXi bone_parts;  ///< #faces: 0 sternum, k left rib k (with its cartilage), -k right rib k
  std::vector<Points3> part_vertices;  ///< per part p (index p + 10): the vertices of its faces
  OrganPlacement pericardium, right_lung, left_lung;
  double heart_shift_mm = 0;  ///< x of the pericardium's centre (left of the midline), mm
  double sternum_back_y_mm =
      0;                       ///< y of the sternum's posterior surface on the midline at the tunnel's level
  double chest_axis_y_mm = 0;  ///< y of the chest's vertical axis (middle of the ribcage's depth there)
  PlannedTunnel tunnel;
  /// Every intercostal space's centre at the port azimuth, both sides (what a port could be).
  std::vector<std::pair<IntercostalSpace, Eigen::Vector3d>> ports;
  /// Every collision triangle (bones, pericardium, lungs) in one grid, with each face's organ.
  Points3 collision_vertices;
  Faces3 collision_faces;
  Eigen::VectorXi collision_organ;
  TriangleGrid collision;
  TriangleGrid bone_grid;
  TriangleGrid pericardium_grid;  ///< coarse cells (15 mm): for distances (scores), not for collisions

  /// The intercostal space that p lies in: p's side, and the two ribs whose local heights (within 12 mm
  /// of p horizontally) bracket p's height, if they are consecutive.
  IntercostalSpace SpaceAt(const Eigen::Vector3d& p) const;
  /// The unsigned distance from p to the pericardium's surface (the ellipsoid its mesh is inscribed in:
  /// the mesh's facets lie within 0.05 mm of it at 4 subdivisions), mm.
  double DistanceToPericardium(const Eigen::Vector3d& p) const;
};

/// Builds the scene of `ribcage` (a fitted patient ribcage). Throws Error(kUsage) for invalid options and
/// Error(kFailure) naming the patient if an organ cannot be placed or no port is found.
TrainerScene BuildTrainerScene(const planner::PatientRibcage& ribcage,
                               const TrainerSceneOptions& options = {});

/// A closed icosphere of `subdivisions` (0-6) scaled to the ellipsoid (centre, semi_axes), outward.
TriangleMesh MakeEllipsoidMesh(const Eigen::Vector3d& centre, const Eigen::Vector3d& semi_axes,
                               int subdivisions);

/// The distance from p to the ellipsoid (centre, semi_axes along x, y, z), mm (Eberly 2013).
double DistanceToEllipsoid(const Eigen::Vector3d& centre, const Eigen::Vector3d& semi_axes,
                           const Eigen::Vector3d& p);

/// The distance from p to the polyline `points` (#points by 3), mm; `beyond_ends` (if given) is set when
/// the nearest point is an end of the polyline and p lies beyond it.
double DistanceToPolyline(const Points3& points, const Eigen::Vector3d& p, bool* beyond_ends = nullptr);

}  // namespace pectus::trainer
