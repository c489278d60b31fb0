#include "planner_plugin/trainer/thoracoscope.h"

#include <gtest/gtest.h>

#include <cmath>

namespace pectus::trainer {
namespace {

constexpr double kDeg = 3.14159265358979323846 / 180.0;

TEST(Thoracoscope, TipPivotsAboutThePort) {
  ScopePose pose;
  pose.port_mm = {-80, -20, -150};
  pose.insertion_mm = 60;
  pose.orientation = Eigen::AngleAxisd(0.4, Eigen::Vector3d(1, 2, 3).normalized());
  // tip = port + R (0, 0, d): 60 mm from the port along the axis, whatever the orientation.
  const Eigen::Vector3d tip = pose.Tip();
  EXPECT_NEAR((tip - pose.port_mm).norm(), 60, 1e-12);
  EXPECT_NEAR((tip - pose.port_mm).normalized().dot(pose.orientation * Eigen::Vector3d::UnitZ()), 1, 1e-12);
}

TEST(Thoracoscope, CameraProjectsKnownPointsWithinHalfAPixelOfThePinholeModel) {
  for (double fov : {70.0, 80.0, 90.0}) {
    ScopeCameraOptions o;
    o.horizontal_fov_deg = fov;
    const ScopeCamera camera(o);
    ScopePose pose;
    pose.port_mm = {-90, 10, -140};
    pose.insertion_mm = 45;
    pose.orientation = Eigen::AngleAxisd(1.1, Eigen::Vector3d(0.3, -1, 0.2).normalized());
    // The pinhole model, written out on its own: f = (W / 2) / tan(fov / 2), the principal point at the
    // centre, the camera turned 30 degrees about the scope's x axis, at the tip.
    const double f = 0.5 * o.width_px / std::tan(0.5 * fov * kDeg);
    const Eigen::Matrix3d R_scene_camera =
        pose.orientation.toRotationMatrix() *
        Eigen::AngleAxisd(30 * kDeg, Eigen::Vector3d::UnitX()).toRotationMatrix();
    const Eigen::Vector3d tip = pose.port_mm + pose.orientation * Eigen::Vector3d(0, 0, 45);
    double worst = 0;
    for (int i = 0; i < 200; ++i) {
      const Eigen::Vector3d p_camera(std::sin(1.3 * i) * 40, std::cos(0.7 * i) * 30, 20 + (i % 17) * 5.0);
      const Eigen::Vector3d point = tip + R_scene_camera * p_camera;
      const Eigen::Vector2d expected(0.5 * (o.width_px - 1) + f * p_camera.x() / p_camera.z(),
                                     0.5 * (o.height_px - 1) + f * p_camera.y() / p_camera.z());
      Eigen::Vector2d pixel;
      ASSERT_TRUE(camera.Project(pose, point, &pixel));
      worst = std::max(worst, (pixel - expected).norm());
      // And back along the pixel's ray.
      EXPECT_LT((camera.Unproject(pose, pixel, p_camera.z()) - point).norm(), 1e-9);
    }
    EXPECT_LT(worst, 0.5);
    EXPECT_LT(worst, 1e-9);  // the same model: exact up to rounding
    // The field of view: a point 40 degrees off the view's axis horizontally lands on the image's edge at 80.
    Eigen::Vector2d edge;
    const Eigen::Vector3d off_axis(std::tan(0.5 * fov * kDeg) * 50, 0, 50);
    ASSERT_TRUE(camera.Project(pose, tip + R_scene_camera * off_axis, &edge));
    EXPECT_NEAR(edge.x(), 0.5 * (o.width_px - 1) + 0.5 * o.width_px, 1e-9);
    // The oblique view: a point straight down the scope's axis appears 30 degrees above the centre.
    Eigen::Vector2d axis_pixel;
    ASSERT_TRUE(camera.Project(pose, tip + pose.orientation * Eigen::Vector3d(0, 0, 50), &axis_pixel));
    EXPECT_NEAR(axis_pixel.y(), 0.5 * (o.height_px - 1) + f * std::tan(30 * kDeg), 1e-9);
    EXPECT_NEAR(axis_pixel.x(), 0.5 * (o.width_px - 1), 1e-9);
    // Behind the camera: not projected.
    EXPECT_FALSE(camera.Project(pose, tip - R_scene_camera * Eigen::Vector3d(0, 0, 10), &edge));
  }
}

}  // namespace
}  // namespace pectus::trainer
