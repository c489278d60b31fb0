// pectus: software rendering of meshes and point clouds to images (orthographic, z-buffer, Lambert
// shading). Enough for documentation and reports; headless, no OpenGL.
#pragma once

#include <Eigen/Core>
#include <optional>

#include "shape/core/geometry.h"
#include "shape/render/image.h"

namespace pectus::render {

/// How to look at the scene. The camera is orthographic: it looks along `direction` with `up` pointing up
/// in the picture, and frames `frame` (or the data's bounds) with a margin.
struct View {
  Eigen::Vector3d direction{0, 0, -1};  ///< viewing direction (from the eye into the scene)
  Eigen::Vector3d up{0, 1, 0};          ///< world direction shown as up in the picture
  int width = 800;                      ///< pixels
  int height = 800;                     ///< pixels
  double margin = 0.05;                 ///< fraction of the picture left empty around the frame
  std::optional<Bounds3> frame;         ///< framed region (mm); default: the bounds of what is drawn.
                                        ///< Give the same frame to pictures that should share a scale.
  Rgb background = kWhite;
  Rgb base_colour{200, 190, 180};  ///< colour where no per-vertex/point colour is given
  bool shading = true;             ///< Lambert shading with a headlight
  int point_radius = 1;            ///< pixels, for point clouds

  /// A view from the front of a chest in the pectus frame (x left-right, y up, z out of the chest).
  static View Front(int width = 800, int height = 800);
  /// A view looking along -x (from the subject's side).
  static View Side(int width = 800, int height = 800);
  /// A view from the front, turned by `yaw_deg` about `up` and tilted by `pitch_deg`.
  static View Oblique(double yaw_deg, double pitch_deg, int width = 800, int height = 800);
};

/// Renders a triangle mesh. Colours: `colors` (#vertices by 3) if given, else the mesh's vertex
/// colours if any, else `view.base_colour`; interpolated across each triangle and shaded.
Image RenderMesh(const TriangleMesh& mesh, const View& view, const Colors3* colors = nullptr);
/// Renders points as small discs. Colours as for RenderMesh; shaded by normal if the cloud has normals.
Image RenderPoints(const PointCloud& cloud, const View& view, const Colors3* colors = nullptr);

}  // namespace pectus::render
