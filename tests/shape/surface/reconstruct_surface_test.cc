#include "shape/surface/reconstruct_surface.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "shape/core/error.h"

namespace pectus {
namespace {

// Points on a sphere of radius r about c (Fibonacci lattice), moved along the radius by Gaussian noise.
PointCloud Sphere(double r, const Eigen::Vector3d& c, int n, double noise_mm) {
  std::mt19937_64 rng(1);
  std::normal_distribution<double> noise(0.0, noise_mm);
  PointCloud cloud;
  cloud.positions.resize(n, 3);
  const double golden = M_PI * (3.0 - std::sqrt(5.0));
  for (int i = 0; i < n; ++i) {
    const double z = 1.0 - 2.0 * (i + 0.5) / n, rho = std::sqrt(1.0 - z * z);
    const Eigen::Vector3d u(rho * std::cos(golden * i), rho * std::sin(golden * i), z);
    cloud.positions.row(i) = (c + (r + noise(rng)) * u).transpose();
  }
  return cloud;
}

// A smooth hill z = f(x, y) over [-60, 60]^2 (slopes under 0.3), the kind of open patch a chest sweep
// gives.
double Hill(double x, double y) {
  return 20.0 * std::exp(-(x * x + y * y) / 5000.0) + 3.0 * std::sin(x / 15.0);
}

// The hill sampled every `step` mm with noise along z, without a disc of diameter hole_mm at (10, -5).
PointCloud HillPatch(double step, double noise_mm, double hole_mm) {
  std::mt19937_64 rng(2);
  std::normal_distribution<double> noise(0.0, noise_mm);
  std::vector<Eigen::Vector3d> pts;
  for (double x = -60; x <= 60; x += step) {
    for (double y = -60; y <= 60; y += step) {
      if (std::hypot(x - 10.0, y + 5.0) < hole_mm / 2) continue;
      pts.emplace_back(x, y, Hill(x, y) + noise(rng));
    }
  }
  PointCloud cloud;
  cloud.positions.resize(Eigen::Index(pts.size()), 3);
  for (std::size_t i = 0; i < pts.size(); ++i) cloud.positions.row(Eigen::Index(i)) = pts[i].transpose();
  return cloud;
}

ReconstructOptions Options(double spacing, double fill) {
  ReconstructOptions o;
  o.spacing_mm = spacing;
  o.fill_holes_mm = fill;
  return o;
}

void ExpectCleanMesh(const ReconstructResult& r) {
  ASSERT_TRUE(r.check.has_value());
  EXPECT_TRUE(r.check->manifold) << r.check->message;
  EXPECT_FALSE(r.check->self_intersecting);
  EXPECT_EQ(r.check->components, 1);
}

TEST(Reconstruct, NoisySphereIsWatertightAndOnTheSphere) {
  const Eigen::Vector3d c(1000.0, -2000.0, 500.0);  // away from the origin
  const PointCloud cloud = Sphere(40.0, c, 20000, 0.05);
  const ReconstructResult r = ReconstructSurface(cloud, Options(1.5, 30.0));
  ExpectCleanMesh(r);
  EXPECT_TRUE(r.check->closed);
  EXPECT_EQ(r.trim.boundary_edges, 0);
  EXPECT_EQ(r.normals_source, "propagated");
  double sum2 = 0, worst = 0;
  for (Eigen::Index v = 0; v < r.mesh.num_vertices(); ++v) {
    const double e = (r.mesh.vertices.positions.row(v).transpose() - c).norm() - 40.0;
    sum2 += e * e;
    worst = std::max(worst, std::abs(e));
    // Normals point out of the sphere.
    EXPECT_GT(
        r.mesh.vertices.normals.row(v).dot((r.mesh.vertices.positions.row(v).transpose() - c).normalized()),
        0.9);
  }
  EXPECT_LT(std::sqrt(sum2 / double(r.mesh.num_vertices())), 0.03) << "noise 0.05 mm is averaged down";
  EXPECT_LT(worst, 0.15);
  // Area of the sphere, 4 pi r^2, within 0.5 %.
  EXPECT_NEAR(r.check->area_mm2, 4.0 * M_PI * 1600.0, 0.005 * 4.0 * M_PI * 1600.0);
  // Fitting accuracy (Carr et al. 2001): max |s(x_i) - f_i| over the constraints, bounded by the noise.
  EXPECT_GT(r.accuracy.fitting_accuracy_mm, 0.0);
  EXPECT_LT(r.accuracy.fitting_accuracy_mm, 0.5);
  EXPECT_LT(r.accuracy.on_surface_rms_mm, 0.06);
}

TEST(Reconstruct, OpenPatchStaysOpenIsTrimmedAndItsHoleIsFilled) {
  const double hole = 24.0;
  const PointCloud cloud = HillPatch(1.0, 0.05, hole);
  const ReconstructResult r = ReconstructSurface(cloud, Options(1.0, 30.0));
  ExpectCleanMesh(r);
  EXPECT_FALSE(r.check->closed) << "an open scan is not closed into a blob";
  EXPECT_EQ(r.trim.holes_filled, 1);
  EXPECT_NEAR(r.trim.largest_hole_filled_mm, hole, 4.0);
  double sum2 = 0, hole_worst = 0;
  Eigen::Index n = 0;
  const Eigen::VectorXd& data_distance = r.mesh.vertices.scalars.at("data_distance");
  for (Eigen::Index v = 0; v < r.mesh.num_vertices(); ++v) {
    const Eigen::Vector3d x = r.mesh.vertices.positions.row(v).transpose();
    // Trimmed to the scanned square plus the margin (the centre spacing) and a grid step.
    EXPECT_LE(std::max(std::abs(x.x()), std::abs(x.y())), 60.0 + r.centre_spacing_mm + r.spacing_mm);
    const double e = std::abs(x.z() - Hill(x.x(), x.y()));  // vertical: slopes are gentle
    if (std::hypot(x.x() - 10.0, x.y() + 5.0) < hole / 2 - 2.0) {
      hole_worst = std::max(hole_worst, e);
    } else if (data_distance(v) < 1.0 && std::max(std::abs(x.x()), std::abs(x.y())) < 55.0) {
      sum2 += e * e;
      ++n;
    }
  }
  EXPECT_LT(std::sqrt(sum2 / double(n)), 0.03) << "where data existed";
  EXPECT_LT(hole_worst, 0.3) << "inside the filled hole";
}

TEST(Reconstruct, HoleWiderThanTheLimitIsLeftOpen) {
  const PointCloud cloud = HillPatch(1.5, 0.0, 24.0);
  ReconstructOptions o = Options(1.5, 10.0);
  o.check = false;
  const ReconstructResult r = ReconstructSurface(cloud, o);
  EXPECT_EQ(r.trim.holes_filled, 0);
  // Cells over a hole wider than the limit find no data ahead within the limit and are not fitted, so
  // the surface is not even made there (holes_left_open counts such regions only when they were made).
  EXPECT_LE(r.trim.holes_left_open, 1);
  double nearest = 1e9;
  for (Eigen::Index v = 0; v < r.mesh.num_vertices(); ++v) {
    const Eigen::Vector3d x = r.mesh.vertices.positions.row(v).transpose();
    const double from_centre = std::hypot(x.x() - 10.0, x.y() + 5.0);
    EXPECT_GT(from_centre, 12.0 - r.centre_spacing_mm - r.spacing_mm);
    nearest = std::min(nearest, from_centre);
  }
  EXPECT_LT(nearest, 12.0 + r.spacing_mm) << "the surface reaches the rim of the hole (radius 12 mm)";
}

TEST(Reconstruct, CoplanarPointsGiveThePlane) {
  PointCloud cloud = HillPatch(1.5, 0.0, 0.0);
  cloud.positions.col(2).setConstant(7.0);
  ReconstructOptions o = Options(1.5, 30.0);
  const ReconstructResult r = ReconstructSurface(cloud, o);
  ExpectCleanMesh(r);
  // The plane lies on a grid plane here; marching cubes keeps vertices 0.1 % of a step off grid corners.
  EXPECT_LE((r.mesh.vertices.positions.col(2).array() - 7.0).abs().maxCoeff(), 1.01e-3 * r.spacing_mm);
}

TEST(Reconstruct, ViewpointOrientsNormalsTowardTheScanner) {
  const PointCloud cloud = HillPatch(1.5, 0.0, 0.0);
  ReconstructOptions o = Options(1.5, 30.0);
  o.check = false;
  o.viewpoint = Eigen::Vector3d(0.0, 0.0, -500.0);  // scanner below: the surface faces down
  const ReconstructResult r = ReconstructSurface(cloud, o);
  EXPECT_EQ(r.normals_source, "viewpoint");
  EXPECT_LT(r.mesh.vertices.normals.col(2).maxCoeff(), 0.0);
}

// Every bad input is a clear Error(kBadInput) naming the cloud, never a crash.
void ExpectBadInput(const PointCloud& cloud, const std::string& fragment) {
  try {
    ReconstructSurface(cloud, Options(1.0, 30.0), "cloud.ply");
    FAIL() << "accepted a cloud that should fail with '" << fragment << "'";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::kBadInput) << e.what();
    EXPECT_NE(std::string(e.what()).find("cloud.ply"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
  }
}

TEST(Reconstruct, BadInputIsAClearError) {
  PointCloud few = Sphere(10.0, Eigen::Vector3d::Zero(), 12, 0.0);
  ExpectBadInput(few, "at least 16");

  PointCloud line;
  line.positions.resize(200, 3);
  for (int i = 0; i < 200; ++i) line.positions.row(i) << 0.5 * i, 2.0 * i, -1.0 * i;
  ExpectBadInput(line, "on one line");

  PointCloud same;
  same.positions = Points3::Constant(100, 3, 4.0);
  ExpectBadInput(same, "same place");

  PointCloud nan = Sphere(10.0, Eigen::Vector3d::Zero(), 500, 0.0);
  nan.positions(17, 1) = std::numeric_limits<double>::quiet_NaN();
  ExpectBadInput(nan, "cloud.ply");

  // Scan lines 20 mm apart with points 0.2 mm apart along them: every neighbourhood is a line.
  PointCloud lines;
  lines.positions.resize(10 * 500, 3);
  for (int l = 0; l < 10; ++l)
    for (int i = 0; i < 500; ++i) lines.positions.row(l * 500 + i) << 0.2 * i, 20.0 * l, 0.01 * l * l;
  ExpectBadInput(lines, "no normals obtainable");

  PointCloud bad_options_cloud = Sphere(10.0, Eigen::Vector3d::Zero(), 500, 0.0);
  ReconstructOptions bad = Options(-1.0, 30.0);
  EXPECT_THROW(ReconstructSurface(bad_options_cloud, bad), Error);
}

}  // namespace
}  // namespace pectus
