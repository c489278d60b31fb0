#include "planner_plugin/host/scope_marker_pose.h"

#include <cmath>
#include <opencv2/aruco.hpp>
#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>
#include <opencv2/imgproc.hpp>

#include "shape/core/error.h"

namespace pectus::trainer {
namespace {

cv::Ptr<cv::aruco::Dictionary> Dictionary() {
  return cv::aruco::getPredefinedDictionary(cv::aruco::DICT_4X4_50);
}

cv::Matx33d Intrinsics(const MarkerCamera& c) { return {c.fx, 0, c.cx, 0, c.fy, c.cy, 0, 0, 1}; }

}  // namespace

bool MarkerOptions::IsValid(std::string* why) const {
  const bool ok = marker_id >= 0 && marker_id < 50 && marker_length_mm > 0;
  if (!ok && why != nullptr) *why = "marker: id 0-49 (DICT_4X4_50) and a length > 0 mm";
  return ok;
}

MarkerPoseResult EstimateMarkerPose(const GrayImage& image, const MarkerCamera& camera,
                                    const MarkerOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) ThrowUsage(why);
  if (image.width <= 0 || image.height <= 0 ||
      image.pixels.size() != static_cast<std::size_t>(image.width) * static_cast<std::size_t>(image.height)) {
    ThrowUsage("marker pose: the image's size does not match its pixels");
  }
  const cv::Mat gray(image.height, image.width, CV_8UC1, const_cast<std::uint8_t*>(image.pixels.data()));
  cv::Ptr<cv::aruco::DetectorParameters> parameters = cv::aruco::DetectorParameters::create();
  parameters->cornerRefinementMethod = cv::aruco::CORNER_REFINE_SUBPIX;
  parameters->cornerRefinementWinSize = 5;
  parameters->cornerRefinementMinAccuracy = 0.001;
  parameters->cornerRefinementMaxIterations = 100;
  std::vector<std::vector<cv::Point2f>> corners, rejected;
  std::vector<int> ids;
  cv::aruco::detectMarkers(gray, Dictionary(), corners, ids, parameters, rejected);
  MarkerPoseResult result;
  for (std::size_t i = 0; i < ids.size(); ++i) {
    if (ids[i] != options.marker_id) continue;
    const double h = 0.5 * options.marker_length_mm;
    const std::vector<cv::Point3d> object = {{-h, h, 0}, {h, h, 0}, {h, -h, 0}, {-h, -h, 0}};
    std::vector<cv::Point2d> seen(corners[i].begin(), corners[i].end());
    cv::Vec3d rvec, tvec;
    const cv::Matx33d K = Intrinsics(camera);
    cv::solvePnP(object, seen, K, cv::noArray(), rvec, tvec, false, cv::SOLVEPNP_IPPE_SQUARE);
    cv::solvePnPRefineLM(object, seen, K, cv::noArray(), rvec, tvec);
    std::vector<cv::Point2d> projected;
    cv::projectPoints(object, rvec, tvec, K, cv::noArray(), projected);
    double sum = 0;
    for (std::size_t k = 0; k < 4; ++k) sum += std::pow(cv::norm(projected[k] - seen[k]), 2);
    cv::Matx33d R;
    cv::Rodrigues(rvec, R);
    Eigen::Matrix3d R_eigen;
    cv::cv2eigen(cv::Mat(R), R_eigen);
    result.found = true;
    result.T_camera_marker.linear() = R_eigen;
    result.T_camera_marker.translation() = Eigen::Vector3d(tvec[0], tvec[1], tvec[2]);
    result.reprojection_rms_px = std::sqrt(sum / 4);
    result.message = "marker " + std::to_string(options.marker_id) + " found";
    return result;
  }
  result.message = "marker " + std::to_string(options.marker_id) + " not in the image (" +
                   std::to_string(ids.size()) + " other markers)";
  return result;
}

GrayImage RenderMarkerView(const MarkerCamera& camera, const Eigen::Isometry3d& T_camera_marker,
                           const MarkerOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) ThrowUsage(why);
  // The marker's image: 6 x 6 cells (4 x 4 bits and the black border) at 100 pixels a cell, with a white
  // quiet zone of a quarter of the side around it.
  constexpr int kSide = 600, kQuiet = 150, kTotal = kSide + 2 * kQuiet;
  cv::Mat marker;
  cv::aruco::drawMarker(Dictionary(), options.marker_id, kSide, marker, 1);
  cv::Mat padded(kTotal, kTotal, CV_8UC1, cv::Scalar(255));
  marker.copyTo(padded(cv::Rect(kQuiet, kQuiet, kSide, kSide)));
  // Marker pixel (u, v) -> plane (X, Y) in mm (pixel centres; y up), then plane -> camera image by
  // K [r1 r2 t], in a 4x supersampled image (pixel centres preserved: c' = 4 (c + 0.5) - 0.5).
  const double mm_per_px = options.marker_length_mm / kSide;
  const double half = 0.5 * kTotal * mm_per_px;
  const cv::Matx33d M(mm_per_px, 0, 0.5 * mm_per_px - half, 0, -mm_per_px, half - 0.5 * mm_per_px, 0, 0, 1);
  constexpr int kSuper = 4;
  const cv::Matx33d K(kSuper * camera.fx, 0, kSuper * (camera.cx + 0.5) - 0.5, 0, kSuper * camera.fy,
                      kSuper * (camera.cy + 0.5) - 0.5, 0, 0, 1);
  const Eigen::Matrix3d R = T_camera_marker.linear();
  const Eigen::Vector3d t = T_camera_marker.translation();
  const cv::Matx33d Rt(R(0, 0), R(0, 1), t.x(), R(1, 0), R(1, 1), t.y(), R(2, 0), R(2, 1), t.z());
  const cv::Matx33d H = K * Rt * M;
  cv::Mat big;
  cv::warpPerspective(padded, big, cv::Mat(H), cv::Size(kSuper * camera.width, kSuper * camera.height),
                      cv::INTER_LINEAR, cv::BORDER_CONSTANT, cv::Scalar(110));
  cv::Mat small;
  cv::resize(big, small, cv::Size(camera.width, camera.height), 0, 0, cv::INTER_AREA);
  GrayImage out;
  out.width = camera.width;
  out.height = camera.height;
  out.pixels.assign(small.datastart, small.dataend);
  return out;
}

}  // namespace pectus::trainer
