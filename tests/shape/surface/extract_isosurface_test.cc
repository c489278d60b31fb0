#include "shape/surface/extract_isosurface.h"

#include <gtest/gtest.h>

#include <cmath>
#include <map>

#include "shape/surface/check_mesh.h"

namespace pectus {
namespace {

// Signed distance to a sphere of radius r about c, NaN where x > cut_x (the field is undefined there).
ScalarField SphereField(const Eigen::Vector3d& c, double r, double cut_x = INFINITY) {
  return [=](const Points3& p, Eigen::VectorXd* v) {
    v->resize(p.rows());
    for (Eigen::Index i = 0; i < p.rows(); ++i) {
      (*v)(i) = p(i, 0) > cut_x ? NAN : (p.row(i).transpose() - c).norm() - r;
    }
  };
}

TEST(MarchingCubes, SphereIsAClosedOutwardManifoldOnTheSphere) {
  const Eigen::Vector3d c(3.3, -1.7, 0.4);
  MarchingCubesOptions o;
  o.spacing_mm = 0.5;
  Points3 seed(1, 3);
  seed << c.x() + 10.0, c.y(), c.z();  // one seed on the surface suffices: the surface is followed
  const MarchingCubesResult r = ExtractIsosurface(SphereField(c, 10.0), seed, o);
  const MeshCheck check = CheckMesh(r.mesh);
  EXPECT_TRUE(check.manifold) << check.message;
  EXPECT_TRUE(check.closed);
  EXPECT_FALSE(check.self_intersecting);
  EXPECT_EQ(check.components, 1);
  EXPECT_EQ(r.mesh.num_vertices() - r.mesh.num_faces() / 2, 2) << "Euler characteristic of a sphere";
  for (Eigen::Index v = 0; v < r.mesh.num_vertices(); ++v) {
    // Linear interpolation on a grid of step h cuts chords: within h^2 / (2 r) of the sphere.
    EXPECT_NEAR((r.mesh.vertices.positions.row(v).transpose() - c).norm(), 10.0, 0.5 * 0.5 / 20.0);
  }
  for (Eigen::Index f = 0; f < r.mesh.num_faces(); ++f) {
    const Eigen::Vector3d a = r.mesh.vertices.positions.row(r.mesh.faces(f, 0)).transpose();
    const Eigen::Vector3d b = r.mesh.vertices.positions.row(r.mesh.faces(f, 1)).transpose();
    const Eigen::Vector3d d = r.mesh.vertices.positions.row(r.mesh.faces(f, 2)).transpose();
    EXPECT_GT((b - a).cross(d - a).dot((a + b + d) / 3.0 - c), 0.0) << "counter-clockwise seen from outside";
  }
  EXPECT_NEAR(check.area_mm2, 4.0 * M_PI * 100.0, 0.01 * 4.0 * M_PI * 100.0);
}

TEST(MarchingCubes, SurfaceStopsWhereTheFieldIsUndefined) {
  MarchingCubesOptions o;
  o.spacing_mm = 0.5;
  Points3 seed(1, 3);
  seed << -10.0, 0.0, 0.0;
  const MarchingCubesResult r = ExtractIsosurface(SphereField(Eigen::Vector3d::Zero(), 10.0, 2.0), seed, o);
  const MeshCheck check = CheckMesh(r.mesh);
  EXPECT_TRUE(check.manifold) << check.message;
  EXPECT_FALSE(check.closed);
  EXPECT_GT(r.undefined_cubes, 0);
  EXPECT_LE(r.mesh.vertices.positions.col(0).maxCoeff(), 2.0 + 1e-9);
}

TEST(MarchingCubes, LimitIsReportedNotExceeded) {
  MarchingCubesOptions o;
  o.spacing_mm = 0.5;
  o.max_cubes = 100;
  Points3 seed(1, 3);
  seed << 9.9, 0.2, 0.3;
  const MarchingCubesResult r = ExtractIsosurface(SphereField(Eigen::Vector3d::Zero(), 10.0), seed, o);
  EXPECT_TRUE(r.reached_limit);
}

}  // namespace
}  // namespace pectus
