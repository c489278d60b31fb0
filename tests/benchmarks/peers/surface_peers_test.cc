#include "tests/benchmarks/peers/surface_peers.h"

#include <gtest/gtest.h>

#include <cmath>

#include "registration/kdtree.h"
#include "shape/surface/reconstruct_surface.h"
#include "tests/shape/mesh_distance.h"
#include "tests/support/synthetic_clouds.h"

namespace pectus {
namespace {

// Same family, same data: pectus' partition-of-unity fit of local polyharmonic splines and PCL's one
// global polyharmonic spline (MarchingCubesRBF) give the same surface on a small noise-free cloud.
TEST(SurfacePeers, AgreesWithPclMarchingCubesRbfOnASmallCloud) {
  const PointCloud cloud = testing_support::EllipsoidCloud(900);
  ReconstructOptions o;
  o.spacing_mm = 0.75;
  o.smoothing = 0.0;  // interpolate, as PCL does
  o.detail_mm = 2.0;  // centres at about the point spacing (2.5 mm), as PCL's one per point
  const ReconstructResult ours = ReconstructSurface(cloud, o);
  ASSERT_TRUE(ours.check && ours.check->closed);
  const TriangleMesh pcl = PclMarchingCubesRbf(cloud, 64, 1.0);

  // Compare where the data are: PCL's global spline may also have zero sets far from the points.
  const KdTree3 data(cloud.positions);
  std::vector<Eigen::Index> near_data;
  for (Eigen::Index v = 0; v < pcl.num_vertices(); ++v) {
    std::uint32_t k;
    double d2;
    if (data.NearestWithin(pcl.vertices.positions.row(v).transpose(), 4.0, &k, &d2)) near_data.push_back(v);
  }
  Points3 pcl_near(Eigen::Index(near_data.size()), 3);
  for (std::size_t i = 0; i < near_data.size(); ++i)
    pcl_near.row(Eigen::Index(i)) = pcl.vertices.positions.row(near_data[i]);
  const Eigen::VectorXd ours_to_pcl = testing::DistancesToMesh(ours.mesh.vertices.positions, pcl);
  const Eigen::VectorXd pcl_to_ours = testing::DistancesToMesh(pcl_near, ours.mesh);
  const double rms1 = std::sqrt(ours_to_pcl.squaredNorm() / double(ours_to_pcl.size()));
  const double rms2 = std::sqrt(pcl_to_ours.squaredNorm() / double(pcl_to_ours.size()));
  auto truth_rms = [](const Points3& p) {  // RMS distance to the ellipsoid, to first order
    double s2 = 0;
    for (Eigen::Index i = 0; i < p.rows(); ++i) {
      const Eigen::Vector3d q = p.row(i).transpose().cwiseQuotient(Eigen::Vector3d(30.0, 22.0, 16.0));
      const Eigen::Vector3d g = 2.0 * q.cwiseQuotient(Eigen::Vector3d(30.0, 22.0, 16.0));
      const double e = (q.squaredNorm() - 1.0) / g.norm();
      s2 += e * e;
    }
    return std::sqrt(s2 / double(p.rows()));
  };
  // Within 0.1 mm everywhere (RMS about 0.01 mm), and both on the ellipsoid.
  EXPECT_LT(ours_to_pcl.maxCoeff(), 0.1);
  EXPECT_LT(pcl_to_ours.maxCoeff(), 0.1);
  EXPECT_LT(rms1, 0.02);
  EXPECT_LT(rms2, 0.02);
  EXPECT_LT(truth_rms(ours.mesh.vertices.positions), 0.02);
  EXPECT_LT(truth_rms(pcl_near), 0.02);
  EXPECT_GT(double(near_data.size()), 0.9 * double(pcl.num_vertices())) << "PCL's surface is the ellipsoid";
}

}  // namespace
}  // namespace pectus
