// The PCL peers of tests/benchmarks/peers/surface_peers.h.
#include <omp.h>
#include <pcl/PolygonMesh.h>
#include <pcl/conversions.h>
#include <pcl/point_types.h>
#include <pcl/surface/marching_cubes_rbf.h>
#include <pcl/surface/poisson.h>

#include "shape/core/error.h"
#include "tests/benchmarks/peers/surface_peers.h"

namespace pectus {
namespace {

pcl::PointCloud<pcl::PointNormal>::Ptr ToPcl(const PointCloud& cloud, const std::string& who) {
  if (!cloud.has_normals()) ThrowBadInput(who, "needs a cloud with normals");
  auto out = pcl::make_shared<pcl::PointCloud<pcl::PointNormal>>();
  out->resize(std::size_t(cloud.size()));
  for (Eigen::Index i = 0; i < cloud.size(); ++i) {
    auto& p = (*out)[std::size_t(i)];
    p.x = float(cloud.positions(i, 0));
    p.y = float(cloud.positions(i, 1));
    p.z = float(cloud.positions(i, 2));
    p.normal_x = float(cloud.normals(i, 0));
    p.normal_y = float(cloud.normals(i, 1));
    p.normal_z = float(cloud.normals(i, 2));
  }
  return out;
}

// PCL's float coordinates are relative to `origin`, so that a cloud far from the origin keeps its detail.
TriangleMesh FromPcl(const pcl::PolygonMesh& mesh, const Eigen::Vector3d& origin, const std::string& who) {
  pcl::PointCloud<pcl::PointXYZ> vertices;
  pcl::fromPCLPointCloud2(mesh.cloud, vertices);
  TriangleMesh out;
  out.vertices.positions.resize(Eigen::Index(vertices.size()), 3);
  for (std::size_t i = 0; i < vertices.size(); ++i) {
    out.vertices.positions.row(Eigen::Index(i)) =
        (vertices[i].getVector3fMap().cast<double>() + origin).transpose();
  }
  std::vector<Eigen::Vector3i> faces;
  for (const auto& polygon : mesh.polygons) {
    for (std::size_t k = 1; k + 1 < polygon.vertices.size(); ++k) {
      faces.emplace_back(int(polygon.vertices[0]), int(polygon.vertices[k]), int(polygon.vertices[k + 1]));
    }
  }
  out.faces.resize(Eigen::Index(faces.size()), 3);
  for (std::size_t f = 0; f < faces.size(); ++f) out.faces.row(Eigen::Index(f)) = faces[f].transpose();
  if (out.num_faces() == 0) ThrowFailure(who + " returned no triangles");
  return out;
}

}  // namespace

TriangleMesh PclPoissonSurface(const PointCloud& cloud, int depth, int threads) {
  const Eigen::Vector3d origin = cloud.positions.colwise().mean().transpose();
  PointCloud centred = cloud;
  centred.positions.rowwise() -= origin.transpose();
  pcl::Poisson<pcl::PointNormal> poisson;
  poisson.setDepth(depth);
  poisson.setThreads(threads > 0 ? threads : omp_get_max_threads());
  poisson.setInputCloud(ToPcl(centred, "PCL Poisson"));
  pcl::PolygonMesh mesh;
  poisson.reconstruct(mesh);
  return FromPcl(mesh, origin, "PCL Poisson");
}

TriangleMesh PclMarchingCubesRbf(const PointCloud& cloud, int resolution, double epsilon_mm, double extend) {
  const Eigen::Vector3d origin = cloud.positions.colwise().mean().transpose();
  PointCloud centred = cloud;
  centred.positions.rowwise() -= origin.transpose();
  pcl::MarchingCubesRBF<pcl::PointNormal> mc;
  mc.setIsoLevel(0.0f);
  mc.setGridResolution(resolution, resolution, resolution);
  mc.setPercentageExtendGrid(float(extend));
  mc.setOffSurfaceDisplacement(float(epsilon_mm));
  mc.setInputCloud(ToPcl(centred, "PCL MarchingCubesRBF"));
  pcl::PolygonMesh mesh;
  mc.reconstruct(mesh);
  return FromPcl(mesh, origin, "PCL MarchingCubesRBF");
}

}  // namespace pectus
