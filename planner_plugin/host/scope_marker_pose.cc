#include "planner_plugin/host/scope_marker_pose.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
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

// The image's intensity at a sub-pixel point (bilinear; pixel centres at integer coordinates).
double Sample(const cv::Mat& gray, double x, double y) {
  const int x0 = std::clamp(static_cast<int>(std::floor(x)), 0, gray.cols - 2);
  const int y0 = std::clamp(static_cast<int>(std::floor(y)), 0, gray.rows - 2);
  const double fx = std::clamp(x - x0, 0.0, 1.0), fy = std::clamp(y - y0, 0.0, 1.0);
  const auto at = [&](int r, int c) { return static_cast<double>(gray.at<std::uint8_t>(r, c)); };
  return (1 - fy) * ((1 - fx) * at(y0, x0) + fx * at(y0, x0 + 1)) +
         fy * ((1 - fx) * at(y0 + 1, x0) + fx * at(y0 + 1, x0 + 1));
}

// The marker's corners refined by fitting a line to each side of its black square and intersecting
// neighbouring sides, as ARToolKit and AprilTag find a square's corners: each side sampled across at 24
// points of its middle 70 %, the edge's sub-pixel position along each from the profile's area, a total
// least-squares line through them. A corner filter
// (cornerSubPix) looks for the saddle of a chessboard's crossing and is pulled towards the inside of an
// L-shaped corner: 0.2-0.3 px on these images (docs/trainer.md). Corners are left as they are when a side
// has too little contrast or too few samples.
void RefineCornersByEdgeLines(const cv::Mat& gray, std::vector<cv::Point2f>* corners) {
  constexpr int kSamples = 24;
  constexpr double kReach = 3.0, kStep = 0.05;
  std::array<Eigen::Vector2d, 4> c;
  for (int i = 0; i < 4; ++i) c[i] = {(*corners)[i].x, (*corners)[i].y};
  const Eigen::Vector2d centre = 0.25 * (c[0] + c[1] + c[2] + c[3]);
  std::array<Eigen::Vector3d, 4> lines;  // a x + b y + c = 0, (a, b) unit
  for (int e = 0; e < 4; ++e) {
    const Eigen::Vector2d a = c[e], b = c[(e + 1) % 4];
    const Eigen::Vector2d along = (b - a).normalized();
    Eigen::Vector2d normal(-along.y(), along.x());
    if (normal.dot(centre - a) > 0) normal = -normal;  // pointing out of the marker (dark to light)
    std::vector<Eigen::Vector2d> points;
    for (int k = 0; k < kSamples; ++k) {
      const Eigen::Vector2d base = a + (0.15 + 0.7 * (k + 0.5) / kSamples) * (b - a);
      // The levels at the profile's ends, then the edge where an ideal step would hold the same amount of
      // light: e = R - integral of (I - dark) / (light - dark) over [-R, R]. Unbiased for any blur that
      // keeps the integral (the pixels' area sampling, bilinear interpolation), where the halfway crossing
      // of interpolated pixels is off by up to 0.1 px.
      double dark = 0, light = 0;
      int ends = 0;
      for (double t = 0; t <= 0.5 + 1e-9; t += kStep, ++ends) {
        const Eigen::Vector2d inside = base + (t - kReach) * normal, outside = base + (kReach - t) * normal;
        dark += Sample(gray, inside.x(), inside.y());
        light += Sample(gray, outside.x(), outside.y());
      }
      dark /= ends;
      light /= ends;
      if (light - dark < 30) continue;
      double area = 0;
      const int steps = static_cast<int>(std::lround(2 * kReach / kStep));
      for (int k2 = 0; k2 <= steps; ++k2) {
        const Eigen::Vector2d p = base + (-kReach + k2 * kStep) * normal;
        const double fraction = (Sample(gray, p.x(), p.y()) - dark) / (light - dark);
        area += (k2 == 0 || k2 == steps ? 0.5 : 1.0) * kStep * fraction;  // trapezoids
      }
      const double best = kReach - area;
      if (std::abs(best) <= kReach) points.push_back(base + best * normal);
    }
    if (points.size() < kSamples / 2) return;
    Eigen::Vector2d mean = Eigen::Vector2d::Zero();
    for (const Eigen::Vector2d& p : points) mean += p;
    mean /= static_cast<double>(points.size());
    Eigen::Matrix2d scatter = Eigen::Matrix2d::Zero();
    for (const Eigen::Vector2d& p : points) scatter += (p - mean) * (p - mean).transpose();
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(scatter);
    const Eigen::Vector2d n = eig.eigenvectors().col(0);  // the smallest spread: the line's normal
    lines[e] = {n.x(), n.y(), -n.dot(mean)};
  }
  for (int i = 0; i < 4; ++i) {  // corner i: the sides before and after it
    const Eigen::Vector3d x = lines[(i + 3) % 4].cross(lines[i]);
    if (std::abs(x.z()) < 1e-9) return;
    const Eigen::Vector2d p = x.head<2>() / x.z();
    if ((p - c[i]).norm() > 2.0) return;  // not the same corner: keep the detector's
    c[i] = p;
  }
  for (int i = 0; i < 4; ++i)
    (*corners)[i] = cv::Point2f(static_cast<float>(c[i].x()), static_cast<float>(c[i].y()));
}

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
    RefineCornersByEdgeLines(gray, &corners[i]);
    std::vector<cv::Point2d> seen(corners[i].begin(), corners[i].end());
    const cv::Matx33d K = Intrinsics(camera);
    // IPPE for a square gives both poses a plane's four points allow (the planar ambiguity: a marker
    // tilted towards or away from the camera); each is refined by Levenberg-Marquardt and the one that
    // reprojects best is kept.
    std::vector<cv::Mat> rvecs, tvecs;
    cv::solvePnPGeneric(object, seen, K, cv::noArray(), rvecs, tvecs, false, cv::SOLVEPNP_IPPE_SQUARE);
    cv::Vec3d rvec, tvec;
    double sum = -1;
    for (std::size_t s = 0; s < rvecs.size(); ++s) {
      cv::Vec3d r = rvecs[s], t = tvecs[s];
      cv::solvePnPRefineLM(object, seen, K, cv::noArray(), r, t);
      std::vector<cv::Point2d> projected;
      cv::projectPoints(object, r, t, K, cv::noArray(), projected);
      double e = 0;
      for (std::size_t k = 0; k < 4; ++k) e += std::pow(cv::norm(projected[k] - seen[k]), 2);
      if (sum < 0 || e < sum) sum = e, rvec = r, tvec = t;
    }
    if (sum < 0) continue;
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
