// pectus trainer, host side: the thoracoscope tracked by a visual marker (the dissertation tracked it with
// ARToolkit, §4.4): an ArUco marker on the scope's handle seen by a calibrated camera, found by OpenCV's
// contrib module; its corners refined by lines fitted to the square's sides (as ARToolKit and AprilTag
// do), its pose by IPPE for a square (both poses of the planar ambiguity), each refined by
// Levenberg-Marquardt, the one reprojecting better kept. Host
// side because the plugin proper links no OpenCV (docs/architecture.md); the interface speaks Eigen and
// plain images, OpenCV stays inside the .cc.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <string>
#include <vector>

namespace pectus::trainer {

/// An 8-bit grey image, row-major.
struct GrayImage {
  int width = 0, height = 0;
  std::vector<std::uint8_t> pixels;  ///< width * height
};

/// A pinhole camera without distortion (pixel centres at integer coordinates).
struct MarkerCamera {
  double fx = 500, fy = 500, cx = 319.5, cy = 239.5;
  int width = 640, height = 480;
};

struct MarkerOptions {
  int marker_id = 7;               ///< in OpenCV's DICT_4X4_50
  double marker_length_mm = 50.0;  ///< side of the black square
  bool IsValid(std::string* why) const;
};

/// T_camera_marker found in an image. The marker frame: origin at the square's centre, x to its right, y
/// up (as printed), z out of its face (OpenCV's convention).
struct MarkerPoseResult {
  bool found = false;
  Eigen::Isometry3d T_camera_marker = Eigen::Isometry3d::Identity();
  double reprojection_rms_px = 0;  ///< of the four corners
  std::string message;
};

/// Finds the marker and its pose. Throws Error(kUsage) for invalid options or an image of the wrong size.
MarkerPoseResult EstimateMarkerPose(const GrayImage& image, const MarkerCamera& camera,
                                    const MarkerOptions& options);

/// The camera's picture of the marker at T_camera_marker on a grey background: the marker's own image
/// (OpenCV's drawing, with a white quiet zone of a quarter of its side) warped by the plane's homography
/// K [r1 r2 t], supersampled 4 times and averaged down. For tests and figures.
GrayImage RenderMarkerView(const MarkerCamera& camera, const Eigen::Isometry3d& T_camera_marker,
                           const MarkerOptions& options);

}  // namespace pectus::trainer
