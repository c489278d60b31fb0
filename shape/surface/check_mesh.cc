#include "shape/surface/check_mesh.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/connected_components.h>
#include <CGAL/Polygon_mesh_processing/measure.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Surface_mesh.h>

#include <array>
#include <chrono>
#include <vector>

namespace pectus {

namespace PMP = CGAL::Polygon_mesh_processing;
using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using SurfaceMesh = CGAL::Surface_mesh<Kernel::Point_3>;

MeshCheck CheckMesh(const TriangleMesh& mesh) {
  const auto start = std::chrono::steady_clock::now();
  MeshCheck check;
  const Eigen::Index nv = mesh.num_vertices();
  std::vector<Kernel::Point_3> points(static_cast<std::size_t>(nv));
  for (Eigen::Index v = 0; v < nv; ++v) {
    points[static_cast<std::size_t>(v)] = {mesh.vertices.positions(v, 0), mesh.vertices.positions(v, 1),
                                           mesh.vertices.positions(v, 2)};
  }
  std::vector<std::array<std::size_t, 3>> polygons(static_cast<std::size_t>(mesh.num_faces()));
  for (Eigen::Index f = 0; f < mesh.num_faces(); ++f) {
    for (int i = 0; i < 3; ++i) {
      const std::int32_t v = mesh.faces(f, i);
      if (v < 0 || v >= nv) {
        check.message =
            "face " + std::to_string(f) + " has vertex index " + std::to_string(v) + " out of range";
        return check;
      }
      polygons[static_cast<std::size_t>(f)][static_cast<std::size_t>(i)] = static_cast<std::size_t>(v);
    }
  }
  auto finish = [&]() {
    check.timings_s.Add("check",
                        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    return check;
  };
  if (!PMP::is_polygon_soup_a_polygon_mesh(polygons)) {
    check.message =
        "not an oriented manifold: an edge has more than two faces or two faces in the same "
        "direction, or a vertex joins more than one fan of faces";
    return finish();
  }
  check.manifold = true;
  SurfaceMesh sm;
  PMP::polygon_soup_to_polygon_mesh(points, polygons, sm);
  for (const auto h : sm.halfedges()) check.border_edges += sm.is_border(h);
  check.closed = check.border_edges == 0;
  auto component = sm.add_property_map<SurfaceMesh::Face_index, std::size_t>("f:component").first;
  check.components = static_cast<std::int64_t>(PMP::connected_components(sm, component));
  check.area_mm2 = PMP::area(sm);
  check.self_intersecting = PMP::does_self_intersect(sm);
  if (check.self_intersecting) check.message = "the surface intersects itself";
  return finish();
}

}  // namespace pectus
