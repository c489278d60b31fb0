// Tests of datasets/surface_query: closest points, signed distances, ray hits and tessellations recover
// points built on the analytic surface.
#include "datasets/surface_query.h"

#include <gtest/gtest.h>

#include "datasets/chest_population.h"

namespace pectus::datasets {
namespace {

ChestSurface Pectus() {
  ChestParameters p = SampleSubject(PopulationModel::Default(), 8).parameters;
  p.pectus.depth_mm = 35.0;
  p.pectus.type = PectusType::kCup;
  return ChestSurface(p);
}

TEST(SurfaceQuery, ClosestPointRecoversTheFootOfANormalOffset) {
  const ChestSurface s = Pectus();
  for (double u : {-0.8, -0.3, 0.0, 0.05, 0.5}) {
    for (double v : {0.1, 0.35, 0.6, 0.85}) {
      const SurfacePoint sp = s.Evaluate(u, v);
      for (double t : {-2.0, -0.5, 0.5, 3.0}) {
        const ClosestPointResult r = ClosestPoint(s, sp.position + t * sp.normal);
        ASSERT_TRUE(r.converged);
        EXPECT_NEAR(r.signed_distance, t, 1e-7) << u << " " << v << " " << t;
        EXPECT_LT((r.point - sp.position).norm(), 1e-5);
      }
    }
  }
}

TEST(SurfaceQuery, RayHitsTheSurfaceWhereItWasAimed) {
  const ChestSurface s = Pectus();
  for (double u : {-0.6, 0.0, 0.4}) {
    for (double v : {0.2, 0.5, 0.8}) {
      const SurfacePoint sp = s.Evaluate(u, v);
      const Eigen::Vector3d direction = -(sp.normal + Eigen::Vector3d(0.2, -0.1, 0.0)).normalized();
      const Eigen::Vector3d origin = sp.position - 150.0 * direction;
      const auto hit = IntersectRay(s, origin, direction, Eigen::Vector2d(u + 0.05, v - 0.03));
      ASSERT_TRUE(hit.has_value());
      EXPECT_LT((hit->point - sp.position).norm(), 1e-6);
      EXPECT_NEAR(hit->t, 150.0, 1e-6);
    }
  }
  // A ray pointing away from the chest misses.
  const SurfacePoint sp = s.Evaluate(0.0, 0.5);
  EXPECT_FALSE(
      IntersectRay(s, sp.position + 100.0 * sp.normal, sp.normal, Eigen::Vector2d(0.0, 0.5)).has_value());
}

TEST(SurfaceQuery, TessellationVerticesLieOnTheSurfaceWithTheRequestedSpacing) {
  const ChestSurface s = Pectus();
  const TriangleMesh mesh = Tessellate(s, 4.0);
  mesh.Validate("tessellation");
  const Eigen::VectorXd& u = mesh.vertices.scalars.at("u");
  const Eigen::VectorXd& v = mesh.vertices.scalars.at("v");
  // Faces come in pairs (a, b, c), (a, c, d) per grid cell: ab runs along u, bc along v.
  double longest = 0.0, sum = 0.0;
  int count = 0;
  for (Eigen::Index f = 0; f < mesh.num_faces(); f += 2) {
    for (int k = 0; k < 2; ++k) {
      const double length =
          (mesh.vertices.positions.row(mesh.faces(f, k)) - mesh.vertices.positions.row(mesh.faces(f, k + 1)))
              .norm();
      longest = std::max(longest, length);
      sum += length;
      ++count;
    }
  }
  // The grid is sized by the fastest the surface moves (sampled): no grid edge is longer than the spacing, up
  // to the sampling of the speed (5 %). (The steep walls of the cup make most other edges much shorter.)
  EXPECT_LT(longest, 4.0 * 1.05);
  EXPECT_GT(sum / count, 0.2 * 4.0);
  for (Eigen::Index k = 0; k < mesh.num_vertices(); k += 97) {
    EXPECT_LT((s.Position(u(k), v(k)) - mesh.vertices.positions.row(k).transpose()).norm(), 1e-12);
  }
  // Triangles face outward: the face normal agrees with the exact normal.
  const Eigen::Vector3d a = mesh.vertices.positions.row(mesh.faces(0, 0)),
                        b = mesh.vertices.positions.row(mesh.faces(0, 1)),
                        c = mesh.vertices.positions.row(mesh.faces(0, 2));
  EXPECT_GT((b - a).cross(c - a).normalized().dot(mesh.vertices.normals.row(mesh.faces(0, 0))), 0.9);
}

}  // namespace
}  // namespace pectus::datasets
