// The CGAL peer of tests/benchmarks/peers/surface_peers.h.
#ifndef CGAL_EIGEN3_ENABLED
#define CGAL_EIGEN3_ENABLED
#endif
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/compute_average_spacing.h>
#include <CGAL/poisson_surface_reconstruction.h>

#include <utility>
#include <vector>

#include "shape/core/error.h"
#include "tests/benchmarks/peers/surface_peers.h"

namespace pectus {

TriangleMesh CgalPoissonSurface(const PointCloud& cloud) {
  using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
  using Point = Kernel::Point_3;
  using Vector = Kernel::Vector_3;
  using PointWithNormal = std::pair<Point, Vector>;
  if (!cloud.has_normals()) ThrowBadInput("CGAL Poisson", "needs a cloud with normals");
  const Eigen::Vector3d origin = cloud.positions.colwise().mean().transpose();
  std::vector<PointWithNormal> points(static_cast<std::size_t>(cloud.size()));
  for (Eigen::Index i = 0; i < cloud.size(); ++i) {
    const Eigen::Vector3d p = cloud.positions.row(i).transpose() - origin;
    points[std::size_t(i)] = {Point(p.x(), p.y(), p.z()),
                              Vector(cloud.normals(i, 0), cloud.normals(i, 1), cloud.normals(i, 2))};
  }
  const double spacing = CGAL::compute_average_spacing<CGAL::Sequential_tag>(
      points, 6, CGAL::parameters::point_map(CGAL::First_of_pair_property_map<PointWithNormal>()));
  CGAL::Surface_mesh<Point> mesh;
  if (!CGAL::poisson_surface_reconstruction_delaunay(
          points.begin(), points.end(), CGAL::First_of_pair_property_map<PointWithNormal>(),
          CGAL::Second_of_pair_property_map<PointWithNormal>(), mesh, spacing)) {
    ThrowFailure("CGAL Poisson reconstruction failed");
  }
  TriangleMesh out;
  out.vertices.positions.resize(Eigen::Index(mesh.number_of_vertices()), 3);
  std::vector<std::int32_t> index(mesh.num_vertices(), -1);
  Eigen::Index k = 0;
  for (const auto v : mesh.vertices()) {
    const Point& p = mesh.point(v);
    out.vertices.positions.row(k) = Eigen::RowVector3d(p.x(), p.y(), p.z()) + origin.transpose();
    index[std::size_t(v)] = std::int32_t(k++);
  }
  out.faces.resize(Eigen::Index(mesh.number_of_faces()), 3);
  Eigen::Index f = 0;
  for (const auto face : mesh.faces()) {
    int c = 0;
    for (const auto v : CGAL::vertices_around_face(mesh.halfedge(face), mesh)) {
      if (c < 3) out.faces(f, c) = index[std::size_t(v)];
      ++c;
    }
    ++f;
  }
  if (out.num_faces() == 0) ThrowFailure("CGAL Poisson reconstruction returned no triangles");
  return out;
}

}  // namespace pectus
