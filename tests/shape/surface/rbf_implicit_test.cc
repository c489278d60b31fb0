#include "shape/surface/rbf_implicit.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "shape/core/error.h"

namespace pectus {
namespace {

// Points and outward normals on a sphere of radius r about c, with a cap of half-angle `cap_deg` around
// +z left out (a hole).
void Sphere(const Eigen::Vector3d& c, double r, int n, double cap_deg, Points3* p, Points3* nrm) {
  std::vector<Eigen::Vector3d> u;
  const double golden = M_PI * (3.0 - std::sqrt(5.0));
  for (int i = 0; i < n; ++i) {
    const double z = 1.0 - 2.0 * (i + 0.5) / n, rho = std::sqrt(1.0 - z * z);
    if (z > std::cos(cap_deg * M_PI / 180.0)) continue;
    u.emplace_back(rho * std::cos(golden * i), rho * std::sin(golden * i), z);
  }
  p->resize(Eigen::Index(u.size()), 3);
  nrm->resize(Eigen::Index(u.size()), 3);
  for (std::size_t i = 0; i < u.size(); ++i) {
    p->row(Eigen::Index(i)) = (c + r * u[i]).transpose();
    nrm->row(Eigen::Index(i)) = u[i].transpose();
  }
}

TEST(RbfImplicit, IsTheSignedDistanceNearTheSurface) {
  const Eigen::Vector3d c(-300.0, 40.0, 2000.0);
  Points3 p, n;
  Sphere(c, 30.0, 12000, 0.0, &p, &n);
  RbfImplicitOptions o;
  o.cell_size_mm = 4.0;
  o.centre_spacing_mm = 2.0;
  o.off_surface_distance_mm = 1.0;
  RbfImplicit s(p, n, o);
  std::mt19937_64 rng(3);
  std::normal_distribution<double> g(0.0, 1.0);
  Points3 q(400, 3);
  Eigen::VectorXd truth(400);
  for (int i = 0; i < 400; ++i) {
    const Eigen::Vector3d dir = Eigen::Vector3d(g(rng), g(rng), g(rng)).normalized();
    truth(i) = -1.0 + 2.0 * (i % 21) / 20.0;  // within 1 mm of the surface, both sides
    q.row(i) = (c + (30.0 + truth(i)) * dir).transpose();
  }
  Eigen::VectorXd v;
  s.Evaluate(q, &v);
  for (int i = 0; i < 400; ++i) EXPECT_NEAR(v(i), truth(i), 0.02 + 0.02 * std::abs(truth(i))) << i;
  const RbfFittingAccuracy acc = s.FittingAccuracy();
  // The on-surface constraints are the points averaged per 1 mm cube (about one point each here).
  EXPECT_GT(acc.num_on_surface, p.rows() / 2);
  EXPECT_LE(acc.num_on_surface, p.rows());
  EXPECT_LT(acc.on_surface_max_mm, 0.01);
  EXPECT_LT(acc.fitting_accuracy_mm, 0.05);
  EXPECT_GE(acc.fitting_accuracy_mm, acc.on_surface_max_mm);
  EXPECT_GT(s.num_cells(), 0);
}

TEST(RbfImplicit, FillsAHoleWithTheSphereAndEndsFarFromData) {
  const Eigen::Vector3d c = Eigen::Vector3d::Zero();
  Points3 p, n;
  Sphere(c, 40.0, 15000, 20.0, &p, &n);  // a hole about 27 mm across at the top
  RbfImplicitOptions o;
  o.cell_size_mm = 4.0;
  o.centre_spacing_mm = 2.0;
  o.max_fill_distance_mm = 20.0;
  RbfImplicit s(p, n, o);
  Points3 q(3, 3);
  q << 0, 0, 40.0,      // the middle of the hole, on the sphere
      0, 0, 39.0,       // inside
      0, 0, 40.0 + 60;  // far from any data
  Eigen::VectorXd v;
  s.Evaluate(q, &v);
  EXPECT_NEAR(v(0), 0.0, 0.3);
  EXPECT_LT(v(1), 0.0);
  EXPECT_TRUE(std::isnan(v(2)));
  EXPECT_GT(s.num_undefined_cells(), 0);
}

TEST(RbfImplicit, RejectsBadOptionsAndSizes) {
  Points3 p, n;
  Sphere(Eigen::Vector3d::Zero(), 10.0, 200, 0.0, &p, &n);
  RbfImplicitOptions o;
  o.cell_size_mm = -1.0;
  std::string why;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_FALSE(why.empty());
  EXPECT_THROW(RbfImplicit(p, n, o), Error);
  EXPECT_THROW(RbfImplicit(p, n.topRows(10), RbfImplicitOptions{}), Error);
}

}  // namespace
}  // namespace pectus
