// pectus: 2D filling of the holes of a grid of heights. The unknown vertices take the values that make
// the surface smoothest, the known ones fixed: the discrete minimiser of the energy
//   E(h) = sum over a + b = q of binom(q, a) * (d^q h / du^a dv^b)^2
// over the grid (q = 2: thin plate, whose interior Euler-Lagrange equation is Delta^2 h = 0; q = 3: the
// next order). Unknown vertices at the grid's border get natural boundary conditions (the energy simply
// has no stencil beyond the grid): q = 2 continues a surface linearly past its data, q = 3 with constant
// curvature, as the 1D P-spline penalties of the same order do (Eilers & Marx 1996).
#pragma once

#include <Eigen/Core>
#include <limits>
#include <string>
#include <vector>

#include "shape/model/profile_fit.h"
#include "shape/model/shape_grid.h"

namespace pectus {

/// How the holes of a grid are filled.
struct GridInpaintingOptions {
  /// Order q of the derivatives in the energy, 2 or 3. Inside a hole the fill reproduces polynomials of
  /// degree 2q - 1 exactly (cubics for q = 2, quintics for q = 3).
  int order = 2;
  /// The lateral axis u is stretched by this factor (> 0) before the energy is taken, u' = stretch * u:
  /// > 1 makes the fill follow the sternal direction v more (a groove along the sternum narrower than
  /// the hole is carried across it along v), 1 is isotropic. 3 is measured best on the virtual scanner's
  /// chests (docs/benchmarks/model.md); the resampler's default.
  double stretch = 3.0;
  /// Half-width (> 0, mm) of the band about the sternal line u = 0 where `stretch` applies in full (about
  /// the sternum's half-width); beyond it the stretch falls linearly to 1 (isotropic) over the same
  /// distance, since the lateral chest wall has no groove along the sternum to carry and bends as much
  /// across as along (border holes: 0.31 mm isotropic, 0.52 mm stretched; docs/benchmarks/model.md).
  /// Infinity: `stretch` everywhere. Takes effect only when the column positions are given (InpaintGrid's
  /// `u_mm`; the resampler gives them).
  double stretch_band_mm = 15.0;

  /// The stretch at lateral position `u_mm`.
  double StretchAt(double u_mm) const;
  /// False, with the reason, for a value out of range.
  bool IsValid(std::string* why) const;
};

/// `values` (row-major on `grid`: vertex i * lateral + j, row i at v_i, column j at u_j) with every vertex
/// where `known` is false replaced by the smoothest fill given the known ones. `spacing_u_mm` and
/// `spacing_v_mm` are the grid spacings across (u) and along (v) the chest (> 0). Throws Error(kUsage) for
/// invalid options or sizes, Error(kFailure) if the known vertices do not determine the fill (none known,
/// or too few for the order). `u_mm`: the columns' lateral positions (mm), for
/// GridInpaintingOptions::stretch_band_mm; empty: `stretch` everywhere.
Eigen::VectorXd InpaintGrid(const GridSize& grid, double spacing_u_mm, double spacing_v_mm,
                            const Eigen::VectorXd& values, const std::vector<bool>& known,
                            const GridInpaintingOptions& options = {},
                            const Eigen::VectorXd& u_mm = Eigen::VectorXd());

/// Which grid vertices the resampler fills in 2D rather than by its section profiles.
enum class GridHoleFill {
  kProfiles,       ///< none: every vertex keeps its row/column profile estimate
  kInpaint,        ///< every hole, those reaching the grid's border with natural boundary conditions
  kInpaintInside,  ///< holes inside the grid; those reaching its border keep the profiles' continuation
};

/// "profiles", "inpaint" or "inpaint-inside"; throws Error(kUsage) otherwise.
GridHoleFill ParseGridHoleFill(const std::string& text);
std::string ToString(GridHoleFill fill);

/// How the resampler fills holes of its grid.
struct GridHoleFillOptions {
  /// Inside holes the 2D fill; holes that reach the grid's border keep the profiles' continuation with
  /// constant curvature (better there than the thin plate's natural, linear continuation: measured).
  GridHoleFill mode = GridHoleFill::kInpaintInside;
  /// Vertices farther than this from the nearest profile data (the grid's "data_gap_mm", >= 0, mm) are
  /// filled in 2D from the others; nearer ones keep their profile estimate.
  double gap_mm = 3.0;
  GridInpaintingOptions inpainting;

  /// False, with the reason, for a value out of range.
  bool IsValid(std::string* why) const;
};

/// Fills the holes of `depth` (per grid vertex, mm) where `gap` (mm, per vertex) exceeds `options.gap_mm`,
/// as `options.mode` says. Returns the number of vertices filled (0 if fewer than 4 order^2 vertices are
/// within the gap: too little to fill from); `filled`, if given, receives per vertex whether it was.
/// `u_mm`: the columns' lateral positions, as for InpaintGrid.
Eigen::Index FillGridHoles(const GridSize& grid, double spacing_u_mm, double spacing_v_mm,
                           const Eigen::VectorXd& gap, const GridHoleFillOptions& options,
                           Eigen::VectorXd* depth, std::vector<bool>* filled = nullptr,
                           const Eigen::VectorXd& u_mm = Eigen::VectorXd());

/// Vertices that no fitted section passes through (a corner beyond the data in both directions): a new
/// profile (`fit`) through the values already `known` along their grid row, then column, extrapolates
/// them, repeated while it fills any; lines with fewer than `min_known` known vertices wait. `u`, `v`:
/// the grid's column and row positions (mm). Each filled vertex's `gap` is the gap of the nearest known
/// vertex on its line plus the distance to it (mm).
void ExtrapolateAlongGridLines(const GridSize& grid, const Eigen::VectorXd& u, const Eigen::VectorXd& v,
                               const ProfileFitOptions& fit, int min_known, std::vector<bool>* known,
                               Eigen::VectorXd* depth, Eigen::VectorXd* gap);

/// Labels the 4-connected components of the vertices where `mask` is true: -1 outside the mask, else the
/// component's number (0, 1, ...). `touches_border` receives, per component, whether it reaches the
/// grid's border.
Eigen::VectorXi LabelGridComponents(const GridSize& grid, const std::vector<bool>& mask,
                                    std::vector<bool>* touches_border);

}  // namespace pectus
