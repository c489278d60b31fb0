// Distance maps: a plane against a shifted plane gives the shift, the sign follows the reference's
// normals, a sphere gives |r - R| at edges and vertices too, nearest-point distances, statistics.
#include "shape/model/distance_map.h"

#include <gtest/gtest.h>

#include <map>
#include <random>

#include "shape/core/error.h"

namespace pectus {
namespace {

// A square grid in the plane z = height, normals +z (counter-clockwise seen from above).
TriangleMesh Plane(double height, int n = 21, double size = 100.0) {
  TriangleMesh m;
  m.vertices.positions.resize(n * n, 3);
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i)
      m.vertices.positions.row(j * n + i) << size * i / (n - 1), size * j / (n - 1), height;
  }
  m.faces.resize(2 * (n - 1) * (n - 1), 3);
  int f = 0;
  for (int j = 0; j + 1 < n; ++j) {
    for (int i = 0; i + 1 < n; ++i) {
      const int a = j * n + i;
      m.faces.row(f++) << a, a + 1, a + n;
      m.faces.row(f++) << a + 1, a + n + 1, a + n;
    }
  }
  return m;
}

// An octahedron subdivided and pushed onto a sphere of radius r (outward normals).
TriangleMesh Sphere(double r, int levels) {
  TriangleMesh m;
  m.vertices.positions.resize(6, 3);
  m.vertices.positions << 1, 0, 0, -1, 0, 0, 0, 1, 0, 0, -1, 0, 0, 0, 1, 0, 0, -1;
  m.faces.resize(8, 3);
  m.faces << 0, 2, 4, 2, 1, 4, 1, 3, 4, 3, 0, 4, 2, 0, 5, 1, 2, 5, 3, 1, 5, 0, 3, 5;
  for (int l = 0; l < levels; ++l) {
    std::map<std::pair<int, int>, int> mid;
    std::vector<Eigen::RowVector3d> p;
    for (Eigen::Index k = 0; k < m.vertices.positions.rows(); ++k) p.push_back(m.vertices.positions.row(k));
    auto middle = [&](int a, int b) {
      const auto key = std::make_pair(std::min(a, b), std::max(a, b));
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      p.push_back((p[a] + p[b]).normalized());
      return mid[key] = static_cast<int>(p.size()) - 1;
    };
    Faces3 f(4 * m.faces.rows(), 3);
    for (Eigen::Index k = 0; k < m.faces.rows(); ++k) {
      const int a = m.faces(k, 0), b = m.faces(k, 1), c = m.faces(k, 2);
      const int ab = middle(a, b), bc = middle(b, c), ca = middle(c, a);
      f.row(4 * k) << a, ab, ca;
      f.row(4 * k + 1) << ab, b, bc;
      f.row(4 * k + 2) << ca, bc, c;
      f.row(4 * k + 3) << ab, bc, ca;
    }
    m.faces = f;
    m.vertices.positions.resize(static_cast<Eigen::Index>(p.size()), 3);
    for (std::size_t k = 0; k < p.size(); ++k) m.vertices.positions.row(static_cast<Eigen::Index>(k)) = p[k];
  }
  m.vertices.positions *= r;
  return m;
}

TEST(DistanceMap, PlaneAgainstAShiftedPlaneIsTheShift) {
  const TriangleMesh reference = Plane(0.0);
  const TriangleMesh above = Plane(2.5, 13), below = Plane(-1.25, 13);
  const DistanceMapResult a = ComputeDistanceMap(above.vertices.positions, reference);
  const DistanceMapResult b = ComputeDistanceMap(below.vertices.positions, reference);
  for (Eigen::Index k = 0; k < a.distances.size(); ++k) {
    EXPECT_NEAR(a.distances[k], 2.5, 1e-12);    // in front of the reference (its normals point +z): positive
    EXPECT_NEAR(b.distances[k], -1.25, 1e-12);  // behind it: negative
  }
  EXPECT_NEAR(a.stats.rms, 2.5, 1e-12);
  EXPECT_NEAR(a.stats.p95, 2.5, 1e-12);
  EXPECT_NEAR(b.stats.min, -1.25, 1e-12);
  EXPECT_NEAR(b.stats.max_abs, 1.25, 1e-12);
  EXPECT_TRUE(a.closest.col(2).isZero(1e-12));
}

TEST(DistanceMap, SignedSurfaceDistanceIsExactOnASphereEverywhere) {
  const TriangleMesh sphere = Sphere(50.0, 4);
  std::mt19937 rng(11);
  std::normal_distribution<double> n(0.0, 1.0);
  std::uniform_real_distribution<double> radius(30.0, 70.0);
  Points3 q(500, 3);
  Eigen::VectorXd expected_sign(500);
  for (int k = 0; k < 500; ++k) {
    const Eigen::Vector3d d = Eigen::Vector3d(n(rng), n(rng), n(rng)).normalized();
    const double r = radius(rng);
    q.row(k) = (r * d).transpose();
    expected_sign[k] = r > 50.0 ? 1.0 : -1.0;
  }
  const DistanceMapResult r = ComputeDistanceMap(q, sphere);
  for (int k = 0; k < 500; ++k) {
    const double radial = q.row(k).norm() - 50.0;
    // A fine polyhedron lies inside the sphere by at most 50 (1 - cos(edge/2R)) ~ 0.08 mm.
    if (std::abs(radial) > 0.2) {
      EXPECT_EQ(r.distances[k] > 0.0 ? 1.0 : -1.0, expected_sign[k]) << k;
    }
    EXPECT_NEAR(std::abs(r.distances[k]), std::abs(radial), 0.2) << k;
    // The closest point is on the surface: brute force agrees.
    double brute = std::numeric_limits<double>::infinity();
    for (Eigen::Index v = 0; v < sphere.num_vertices(); ++v)
      brute = std::min(brute, (sphere.vertices.positions.row(v) - q.row(k)).norm());
    EXPECT_LE(std::abs(r.distances[k]), brute + 1e-9);
  }
}

TEST(DistanceMap, NearestPointUsesVerticesOnly) {
  TriangleMesh cloud = Plane(0.0, 3, 10.0);  // vertices every 5 mm
  cloud.faces.resize(0, 3);
  Points3 q(2, 3);
  q << 5, 5, 4, 2.5, 0, 0;
  const DistanceMapResult r = ComputeDistanceMap(q, cloud, DistanceKind::kNearestPoint);
  EXPECT_NEAR(r.distances[0], 4.0, 1e-12);
  EXPECT_NEAR(r.distances[1], 2.5, 1e-12);
  EXPECT_THROW(ComputeDistanceMap(q, cloud, DistanceKind::kSignedSurface, "cloud.ply"), Error);
}

TEST(DistanceMap, StatisticsOfKnownValues) {
  Eigen::VectorXd d(5);
  d << -4, -1, 0, 1, 2;
  const DistanceStats s = SummarizeDistances(d);
  EXPECT_EQ(s.count, 5);
  EXPECT_DOUBLE_EQ(s.min, -4);
  EXPECT_DOUBLE_EQ(s.max, 2);
  EXPECT_DOUBLE_EQ(s.max_abs, 4);
  EXPECT_DOUBLE_EQ(s.mean, -0.4);
  EXPECT_DOUBLE_EQ(s.mean_abs, 1.6);
  EXPECT_DOUBLE_EQ(s.rms, std::sqrt(22.0 / 5.0));
  EXPECT_DOUBLE_EQ(s.p50, 1.0);  // |d| sorted: 0 1 1 2 4
  EXPECT_DOUBLE_EQ(s.p90, 3.2);  // 2 + 0.6 (4 - 2)
  EXPECT_EQ(s.ToJson()["max_abs_mm"], 4.0);
  EXPECT_EQ(ParseDistanceKind("nearest"), DistanceKind::kNearestPoint);
  EXPECT_THROW(ParseDistanceKind("hausdorff"), Error);
}

}  // namespace
}  // namespace pectus
