// pectus trainer: the thoracoscope as the trainer sees it: a rigid scope pivoting at its port in the chest
// wall, tip = port + R (0, 0, d) (R its orientation, from the inertial filter or the markers; d how far it
// is in), and its camera at the tip: an oblique optic (30 degrees off the scope's axis, as the scopes of
// thoracoscopic Nuss procedures are) with a pinhole projection of 70-90 degrees field of view.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <string>

namespace pectus::trainer {

/// The scope's pose: R_scene_scope (its axis, handle to tip, is R (0, 0, 1)), the port, the depth.
struct ScopePose {
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();
  Eigen::Vector3d port_mm = Eigen::Vector3d::Zero();
  double insertion_mm = 0;  ///< from the port to the tip along the axis
  /// tip = port + R (0, 0, d).
  Eigen::Vector3d Tip() const { return port_mm + orientation * Eigen::Vector3d(0, 0, insertion_mm); }
};

struct ScopeCameraOptions {
  double oblique_deg = 30.0;         ///< the view's angle from the scope's axis, towards the scope's -y
  double horizontal_fov_deg = 80.0;  ///< 70-90 for thoracoscopes
  int width_px = 640, height_px = 480;
  bool IsValid(std::string* why) const;
};

/// The camera at the scope's tip. Camera frame: z along the view, x to the image's right, y down;
/// square pixels, the principal point at the image's centre; pixel (0, 0) is the centre of the top-left
/// pixel.
class ScopeCamera {
 public:
  /// Throws Error(kUsage) for invalid options.
  explicit ScopeCamera(const ScopeCameraOptions& options = {});
  /// R_scope_camera: the oblique turn about the scope's x axis.
  Eigen::Matrix3d ScopeFromCamera() const;
  /// T_scene_camera for a pose.
  Eigen::Isometry3d SceneFromCamera(const ScopePose& pose) const;
  /// The pixel of a scene point (mm); false (pixel untouched) behind the camera.
  bool Project(const ScopePose& pose, const Eigen::Vector3d& point_mm, Eigen::Vector2d* pixel) const noexcept;
  /// The scene point at `depth_mm` along the ray of `pixel`.
  Eigen::Vector3d Unproject(const ScopePose& pose, const Eigen::Vector2d& pixel, double depth_mm) const;
  double focal_px() const { return focal_px_; }
  Eigen::Vector2d principal_point() const {
    return {0.5 * (options_.width_px - 1), 0.5 * (options_.height_px - 1)};
  }
  const ScopeCameraOptions& options() const { return options_; }

 private:
  ScopeCameraOptions options_;
  double focal_px_ = 1;
};

}  // namespace pectus::trainer
