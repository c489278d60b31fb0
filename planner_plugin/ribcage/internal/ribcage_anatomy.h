// pectus planner: the anatomy of the generic (average) ribcage in figures: where each rib runs, the
// sternum's width and thickness along its arc, and the shell the rib centre lines lie on. The builder
// (build_generic_ribcage.cc) sweeps and meshes them.
#pragma once

#include "planner_plugin/ribcage/chest_shell.h"

namespace pectus::planner {

/// Anatomy of one left rib of the generic ribcage, mm, in the frame of ChestShell. Rib heads sit one
/// vertebra (21.7 mm) apart, the sternal notch at the level of the T2/T3 disc. The costochondral
/// junctions (x, z) descend laterally; ribs 1-7 join the sternum at `sternal_fraction` of its arc; ribs
/// 8-10 join the lower border of the cartilage above, kMarginFraction along it.
struct RibAnatomy {
  double head_z;            ///< z of the rib head (costovertebral joint)
  double junction_x;        ///< costochondral junction: lateral position
  double junction_z;        ///<   and height
  double sternal_fraction;  ///< ribs 1-7: centre of the sternocostal joint along the sternal arc
  double shaft_height;      ///< rib height (cranio-caudal extent of its section)
  double shaft_thickness;   ///< rib thickness (radial)
};
inline constexpr double kRibHeadX = 22.0;         ///< lateral position of the rib heads, mm
inline constexpr double kMarginFraction = 0.5;    ///< where a false rib's cartilage meets the cartilage above
inline constexpr double kCartilageHeight = 12.0;  ///< costal cartilage section, mm
inline constexpr double kCartilageThickness = 9.0;
/// Ribs 1 to 10.
inline constexpr RibAnatomy kRibs[10] = {
    {32.0, 50, -15, 0.11, 16.0, 6.0},    {10.3, 58, -40, 0.29, 13.0, 6.5},
    {-11.4, 70, -68, 0.42, 13.0, 6.5},   {-33.1, 80, -95, 0.54, 13.0, 6.5},
    {-54.8, 88, -120, 0.65, 13.0, 6.5},  {-76.5, 95, -145, 0.75, 13.0, 6.5},
    {-98.2, 102, -168, 0.87, 13.0, 6.5}, {-119.9, 112, -202, 0, 13.0, 6.5},
    {-141.6, 118, -226, 0, 12.0, 6.5},   {-163.3, 120, -248, 0, 11.0, 6.0}};

/// Sternum width along its arc fraction f, mm (manubrium 0-0.29, body 0.29-0.9, xiphoid 0.9-1).
const SmoothProfile& SternumWidth();
/// Sternum thickness along its arc fraction f, mm.
const SmoothProfile& SternumThickness();
/// Arc fractions where the manubrium and the sternal body end.
inline constexpr double kManubriumEnd = 0.29, kBodyEnd = 0.90;

/// The shell of the rib centre lines: half-width and half-depth per height, the sternum leaning forward
/// by `tilt_rad`.
ChestShell MakeShell(double tilt_rad);

}  // namespace pectus::planner
