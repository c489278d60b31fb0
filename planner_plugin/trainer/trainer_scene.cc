#include "planner_plugin/trainer/trainer_scene.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <utility>

#include "shape/core/error.h"

namespace pectus::trainer {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr int kRibs = 10;

// The smallest distance between the vertices of `a` and the surface of grid `b`, and back, up to `reach`.
double Clearance(const Points3& a, const TriangleGrid& b_grid, const Points3& b, const TriangleGrid& a_grid,
                 double reach) {
  double best = reach;
  SurfaceHit hit;
  for (Eigen::Index i = 0; i < a.rows(); ++i) {
    if (b_grid.Nearest(a.row(i).transpose(), best, &hit)) best = std::min(best, hit.distance_mm);
  }
  for (Eigen::Index i = 0; i < b.rows(); ++i) {
    if (a_grid.Nearest(b.row(i).transpose(), best, &hit)) best = std::min(best, hit.distance_mm);
  }
  return best;
}

// Whether p lies inside the closed ellipsoid.
bool InsideEllipsoid(const OrganPlacement& o, const Eigen::Vector3d& p) {
  return ((p - o.centre).array() / o.semi_axes.array()).matrix().squaredNorm() < 1.0;
}

// The vertices of the bone faces of each part (index part + kRibs), deduplicated.
std::vector<Points3> VerticesByPart(const Points3& vertices, const Faces3& faces,
                                    const Eigen::VectorXi& parts) {
  std::vector<std::vector<std::int32_t>> ids(2 * kRibs + 1);
  for (Eigen::Index f = 0; f < faces.rows(); ++f) {
    const int part = parts(f);
    if (part < -kRibs || part > kRibs) continue;
    for (int i = 0; i < 3; ++i) ids[static_cast<std::size_t>(part + kRibs)].push_back(faces(f, i));
  }
  std::vector<Points3> out(ids.size());
  for (std::size_t k = 0; k < ids.size(); ++k) {
    std::sort(ids[k].begin(), ids[k].end());
    ids[k].erase(std::unique(ids[k].begin(), ids[k].end()), ids[k].end());
    out[k].resize(static_cast<Eigen::Index>(ids[k].size()), 3);
    for (std::size_t i = 0; i < ids[k].size(); ++i)
      out[k].row(static_cast<Eigen::Index>(i)) = vertices.row(ids[k][i]);
  }
  return out;
}

// Uniform Catmull-Rom through `knots`, sampled about every `step_mm`.
Points3 CatmullRom(const std::vector<Eigen::Vector3d>& knots, double step_mm) {
  std::vector<Eigen::Vector3d> out;
  const int n = static_cast<int>(knots.size());
  for (int i = 0; i + 1 < n; ++i) {
    const Eigen::Vector3d& p0 = knots[static_cast<std::size_t>(std::max(i - 1, 0))];
    const Eigen::Vector3d& p1 = knots[static_cast<std::size_t>(i)];
    const Eigen::Vector3d& p2 = knots[static_cast<std::size_t>(i + 1)];
    const Eigen::Vector3d& p3 = knots[static_cast<std::size_t>(std::min(i + 2, n - 1))];
    const int steps = std::max(1, static_cast<int>(std::ceil((p2 - p1).norm() / step_mm)));
    for (int s = 0; s < steps; ++s) {
      const double t = static_cast<double>(s) / steps, t2 = t * t, t3 = t2 * t;
      out.push_back(0.5 * ((2 * p1) + (-p0 + p2) * t + (2 * p0 - 5 * p1 + 4 * p2 - p3) * t2 +
                           (-p0 + 3 * p1 - 3 * p2 + p3) * t3));
    }
  }
  out.push_back(knots.back());
  Points3 points(static_cast<Eigen::Index>(out.size()), 3);
  for (std::size_t i = 0; i < out.size(); ++i) points.row(static_cast<Eigen::Index>(i)) = out[i];
  return points;
}

}  // namespace

std::string IntercostalSpace::Name() const {
  if (side == 0 || number == 0) return "none";
  return std::string(side < 0 ? "right " : "left ") + std::to_string(number);
}

bool TrainerSceneOptions::IsValid(std::string* why) const {
  auto fail = [&](const std::string& m) {
    if (why != nullptr) *why = m;
    return false;
  };
  if (!(mediastinal_gap_mm > 0 && mediastinal_gap_mm < 40))
    return fail("mediastinal_gap_mm must be in (0, 40)");
  if (!(pleural_gap_mm > 0 && pleural_gap_mm < 60)) return fail("pleural_gap_mm must be in (0, 60)");
  if (!(heart_fractions.array() > 0).all() || !(heart_fractions.array() < 1).all())
    return fail("heart_fractions must be in (0, 1)");
  if (!(port_azimuth_deg > 20 && port_azimuth_deg < 100))
    return fail("port_azimuth_deg must be in (20, 100)");
  if (!(heart_level > 0.3 && heart_level < 1.2)) return fail("heart_level must be in (0.3, 1.2)");
  if (organ_subdivisions < 0 || organ_subdivisions > 6) return fail("organ_subdivisions must be 0 to 6");
  if (!(grid_cell_mm >= 1 && grid_cell_mm <= 50)) return fail("grid_cell_mm must be 1 to 50");
  if (!(port_inset_mm >= 0 && port_inset_mm < 40)) return fail("port_inset_mm must be 0 to 40");
  return true;
}

TriangleMesh MakeEllipsoidMesh(const Eigen::Vector3d& centre, const Eigen::Vector3d& semi_axes,
                               int subdivisions) {
  // Icosahedron, then each triangle split in four with the midpoints pushed to the unit sphere.
  const double g = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<Eigen::Vector3d> v = {{-1, g, 0}, {1, g, 0}, {-1, -g, 0}, {1, -g, 0},
                                    {0, -1, g}, {0, 1, g}, {0, -1, -g}, {0, 1, -g},
                                    {g, 0, -1}, {g, 0, 1}, {-g, 0, -1}, {-g, 0, 1}};
  std::vector<Eigen::Vector3i> f = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                                    {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                    {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                                    {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  for (auto& p : v) p.normalize();
  for (int s = 0; s < subdivisions; ++s) {
    std::map<std::pair<int, int>, int> midpoint;
    auto mid = [&](int a, int b) {
      const auto key = std::minmax(a, b);
      const auto it = midpoint.find(key);
      if (it != midpoint.end()) return it->second;
      v.push_back((v[static_cast<std::size_t>(a)] + v[static_cast<std::size_t>(b)]).normalized());
      return midpoint[key] = static_cast<int>(v.size()) - 1;
    };
    std::vector<Eigen::Vector3i> next;
    for (const auto& t : f) {
      const int a = mid(t(0), t(1)), b = mid(t(1), t(2)), c = mid(t(2), t(0));
      next.insert(next.end(), {{t(0), a, c}, {t(1), b, a}, {t(2), c, b}, {a, b, c}});
    }
    f.swap(next);
  }
  TriangleMesh mesh;
  mesh.vertices.positions.resize(static_cast<Eigen::Index>(v.size()), 3);
  for (std::size_t i = 0; i < v.size(); ++i) {
    mesh.vertices.positions.row(static_cast<Eigen::Index>(i)) = centre + v[i].cwiseProduct(semi_axes);
  }
  mesh.faces.resize(static_cast<Eigen::Index>(f.size()), 3);
  for (std::size_t i = 0; i < f.size(); ++i) mesh.faces.row(static_cast<Eigen::Index>(i)) = f[i].transpose();
  return mesh;
}

double DistanceToPolyline(const Points3& points, const Eigen::Vector3d& p, bool* beyond_ends) {
  double best = std::numeric_limits<double>::infinity();
  bool beyond = false;
  const Eigen::Index last = points.rows() - 1;
  for (Eigen::Index i = 0; i < last; ++i) {
    const Eigen::Vector3d a = points.row(i), b = points.row(i + 1), d = b - a;
    const double len2 = d.squaredNorm();
    const double raw = len2 > 0 ? (p - a).dot(d) / len2 : 0.0;
    const double t = std::clamp(raw, 0.0, 1.0);
    const double dist2 = (a + t * d - p).squaredNorm();
    if (dist2 < best) {
      best = dist2;
      beyond = (i == 0 && raw < 0) || (i + 1 == last && raw > 1);
    }
  }
  if (points.rows() == 1) best = (points.row(0).transpose() - p).squaredNorm(), beyond = true;
  if (beyond_ends != nullptr) *beyond_ends = beyond;
  return std::sqrt(best);
}

IntercostalSpace TrainerScene::SpaceAt(const Eigen::Vector3d& p) const {
  const std::vector<Points3>& by_part = part_vertices;
  const int side = p.x() < 0 ? -1 : 1;
  constexpr double kReach = 12.0;
  double above = std::numeric_limits<double>::infinity(), below = -std::numeric_limits<double>::infinity();
  int rib_above = 0, rib_below = 0;
  for (int k = 1; k <= kRibs; ++k) {
    const Points3& v = by_part[static_cast<std::size_t>(side * k + kRibs)];
    double sum = 0;
    int n = 0;
    for (Eigen::Index i = 0; i < v.rows(); ++i) {
      if (std::hypot(v(i, 0) - p.x(), v(i, 1) - p.y()) < kReach) {
        sum += v(i, 2);
        ++n;
      }
    }
    if (n == 0) continue;
    const double z = sum / n;
    if (z > p.z() && z < above) above = z, rib_above = k;
    if (z <= p.z() && z > below) below = z, rib_below = k;
  }
  if (rib_above == 0 || rib_below != rib_above + 1) return {};
  return {side, rib_above};
}

double DistanceToEllipsoid(const Eigen::Vector3d& centre, const Eigen::Vector3d& semi_axes,
                           const Eigen::Vector3d& p) {
  // Eberly, "Distance from a point to an ellipse, an ellipsoid, or a hyperellipsoid" (2013): in the
  // first octant, the nearest point is y_i a_i^2 / (t + a_i^2) with t the root of
  // F(t) = sum (a_i y_i / (t + a_i^2))^2 - 1, found by bisection.
  const Eigen::Vector3d y = (p - centre).cwiseAbs();
  const Eigen::Vector3d a2 = semi_axes.cwiseProduct(semi_axes);
  const double inside = (y.array() / semi_axes.array()).square().sum();
  if (inside == 1) return 0;
  auto F = [&](double t) { return (semi_axes.array() * y.array() / (t + a2.array())).square().sum() - 1; };
  const double amin = a2.minCoeff();
  double lo = -amin + 1e-12 * amin, hi = (y.norm() + semi_axes.maxCoeff()) * semi_axes.maxCoeff();
  if (inside > 1)
    lo = 0;
  else
    hi = 0;
  for (int it = 0; it < 200 && hi - lo > 1e-12 * (1 + std::abs(hi)); ++it) {
    const double mid = 0.5 * (lo + hi);
    (F(mid) > 0 ? lo : hi) = mid;
  }
  const double t = 0.5 * (lo + hi);
  const Eigen::Vector3d x = (a2.array() * y.array() / (t + a2.array())).matrix();
  return (x - y).norm();
}

double TrainerScene::DistanceToPericardium(const Eigen::Vector3d& p) const {
  return DistanceToEllipsoid(pericardium.centre, pericardium.semi_axes, p);
}

TrainerScene BuildTrainerScene(const planner::PatientRibcage& ribcage, const TrainerSceneOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) ThrowUsage("trainer scene: " + why);
  const std::string who = "trainer scene of patient " + ribcage.patient + ": ";
  TrainerScene scene;
  scene.patient = ribcage.patient;
  scene.bone_vertices = ribcage.surface.nodes;
  scene.bone_faces = ribcage.surface.faces;
  scene.bone_parts = ribcage.surface.face_parts;
  scene.bone_grid = TriangleGrid(scene.bone_vertices, scene.bone_faces, options.grid_cell_mm);
  Points3 bone_surface_vertices;  // the vertices on faces (the ribcage's nodes include inner ones)
  {
    std::vector<std::int32_t> used(scene.bone_faces.data(),
                                   scene.bone_faces.data() + scene.bone_faces.size());
    std::sort(used.begin(), used.end());
    used.erase(std::unique(used.begin(), used.end()), used.end());
    bone_surface_vertices.resize(static_cast<Eigen::Index>(used.size()), 3);
    for (std::size_t i = 0; i < used.size(); ++i) {
      bone_surface_vertices.row(static_cast<Eigen::Index>(i)) = scene.bone_vertices.row(used[i]);
    }
  }
  const planner::RibcageMeasurements& m = ribcage.measured;
  const double L = m.sternal_length_mm, z_t = m.slice_z_mm;

  // The sternum's back on the midline at the bar's level: the last crossing of the sternum's faces along y.
  std::vector<SurfaceHit> hits;
  scene.bone_grid.AllHits({0, -400, z_t}, {0, 400, z_t}, &hits);
  double y_back = std::numeric_limits<double>::quiet_NaN();
  for (const SurfaceHit& h : hits) {
    if (scene.bone_parts(h.face) == 0) y_back = h.point.y();
  }
  if (!std::isfinite(y_back))
    ThrowFailure(who + "no sternum on the midline at the slice of deepest depression");
  scene.sternum_back_y_mm = y_back;
  // The chest's axis: the middle of the ribs' extent in y near the level.
  double y_min = std::numeric_limits<double>::infinity(), y_max = -y_min;
  for (Eigen::Index i = 0; i < scene.bone_vertices.rows(); ++i) {
    if (std::abs(scene.bone_vertices(i, 2) - z_t) < 10) {
      y_min = std::min(y_min, scene.bone_vertices(i, 1));
      y_max = std::max(y_max, scene.bone_vertices(i, 1));
    }
  }
  scene.chest_axis_y_mm = 0.5 * (y_min + y_max);

  // 1. The pericardium: an ellipsoid scaled with the chest, shifted left with the depression, moved
  //    forward until its nearest approach to any bone is the mediastinal gap (bisection on y).
  OrganPlacement& heart = scene.pericardium;
  Eigen::Vector3d heart_axes(options.heart_fractions.x() * m.width_mm,
                             options.heart_fractions.y() * m.depth_mm, options.heart_fractions.z() * L);
  scene.heart_shift_mm = options.heart_shift_mm + options.heart_shift_per_depression * m.depression_mm;
  const double heart_z = m.notch_z_mm - options.heart_level * L;
  auto place = [&](OrganPlacement* o, const Eigen::Vector3d& centre, const Eigen::Vector3d& axes) {
    o->centre = centre;
    o->semi_axes = axes;
    o->mesh = MakeEllipsoidMesh(centre, axes, options.organ_subdivisions);
  };
  const double gap = options.mediastinal_gap_mm;
  auto clearance_at = [&](double y) {
    place(&heart, {scene.heart_shift_mm, y, heart_z}, heart_axes);
    if (InsideEllipsoid(heart, {0, y_back - 1, z_t})) return 0.0;  // swallowed the sternum
    const TriangleGrid g(heart.mesh.vertices.positions, heart.mesh.faces, options.grid_cell_mm);
    return Clearance(heart.mesh.vertices.positions, scene.bone_grid, bone_surface_vertices, g, 2 * gap);
  };
  // From touching the sternum's back, step back until the gap holds, then bisect the last step; a heart
  // that finds no such place between the sternum and the spine is made 5 % smaller and tried again.
  double y_ok = std::numeric_limits<double>::quiet_NaN();
  for (int shrink = 0; shrink < 20 && !std::isfinite(y_ok); ++shrink) {
    const double first = y_back + heart_axes.y() * 0.5, last = y_back + m.depth_mm;
    for (double y = first; y <= last; y += 2.0) {
      if (clearance_at(y) >= gap) {
        double lo = y - 2.0, hi = y;
        for (int it = 0; it < 30 && hi - lo > 1e-3; ++it) {
          const double mid = 0.5 * (lo + hi);
          (clearance_at(mid) >= gap ? hi : lo) = mid;
        }
        y_ok = hi;
        break;
      }
    }
    if (!std::isfinite(y_ok)) heart_axes *= 0.95;
  }
  if (!std::isfinite(y_ok)) ThrowFailure(who + "no place for the pericardium behind the sternum");
  place(&heart, {scene.heart_shift_mm, y_ok, heart_z}, heart_axes);
  scene.pericardium_grid =
      TriangleGrid(heart.mesh.vertices.positions, heart.mesh.faces, options.grid_cell_mm);

  // 2. The lungs: ellipsoids beside the heart, shrunk about their centres until they keep the pleural gap
  //    from every bone and 2 mm from the pericardium.
  for (int side : {-1, 1}) {
    OrganPlacement& lung = side < 0 ? scene.right_lung : scene.left_lung;
    const Eigen::Vector3d centre(side * 0.25 * m.width_mm, scene.chest_axis_y_mm + 0.1 * m.depth_mm,
                                 m.notch_z_mm - 0.5 * L);
    const Eigen::Vector3d axes(0.17 * m.width_mm, 0.38 * m.depth_mm, 0.5 * L);
    double lo = 0.05, hi = 1.0;
    for (int it = 0; it < 14; ++it) {
      const double s = 0.5 * (lo + hi);
      place(&lung, centre, s * axes);
      const TriangleGrid g(lung.mesh.vertices.positions, lung.mesh.faces, options.grid_cell_mm);
      const bool ok = Clearance(lung.mesh.vertices.positions, scene.bone_grid, scene.bone_vertices, g,
                                options.pleural_gap_mm) >= options.pleural_gap_mm &&
                      Clearance(lung.mesh.vertices.positions, scene.pericardium_grid,
                                heart.mesh.vertices.positions, g, 2.0) >= 2.0;
      (ok ? lo : hi) = s;
    }
    place(&lung, centre, lo * axes);
  }

  // 3. The ports: on each side, where the ribs cross the half-plane at the port azimuth about the chest's
  //    axis; the gap between consecutive ribs whose centre is nearest the bar's level.
  scene.part_vertices = VerticesByPart(scene.bone_vertices, scene.bone_faces, scene.bone_parts);
  const std::vector<Points3>& by_part = scene.part_vertices;
  const double azimuth = options.port_azimuth_deg * kPi / 180;
  Eigen::Vector3d ports[2];
  IntercostalSpace spaces[2];
  for (int s = 0; s < 2; ++s) {
    const int side = s == 0 ? -1 : 1;
    std::vector<std::pair<int, Eigen::Vector3d>> crossings;
    for (int k = 1; k <= kRibs; ++k) {
      const Points3& v = by_part[static_cast<std::size_t>(side * k + kRibs)];
      Eigen::Vector3d sum = Eigen::Vector3d::Zero();
      int n = 0;
      for (Eigen::Index i = 0; i < v.rows(); ++i) {
        const double a = std::atan2(side * v(i, 0), -(v(i, 1) - scene.chest_axis_y_mm));
        if (std::abs(a - azimuth) < 3 * kPi / 180) sum += v.row(i).transpose(), ++n;
      }
      if (n > 0) crossings.emplace_back(k, sum / n);
    }
    double best = std::numeric_limits<double>::infinity();
    for (std::size_t i = 0; i + 1 < crossings.size(); ++i) {
      if (crossings[i + 1].first != crossings[i].first + 1) continue;
      const Eigen::Vector3d c = 0.5 * (crossings[i].second + crossings[i + 1].second);
      scene.ports.push_back({{side, crossings[i].first}, c});
      if (std::abs(c.z() - z_t) < best) {
        best = std::abs(c.z() - z_t);
        ports[s] = c;
        spaces[s] = {side, crossings[i].first};
      }
    }
    if (!std::isfinite(best)) ThrowFailure(who + "no intercostal space at the port azimuth");
  }

  // 4. The tunnel: port, inside the wall behind it, along the inside of the anterior wall, under the
  //    sternum in the middle of the mediastinal gap, and out the same way on the left.
  auto inner_wall = [&](double x) {  // the anterior wall's inner surface at x near the bar's level
    double y = -std::numeric_limits<double>::infinity();
    for (Eigen::Index i = 0; i < scene.bone_vertices.rows(); ++i) {
      const Eigen::RowVector3d v = scene.bone_vertices.row(i);
      if (std::abs(v.x() - x) < 5 && std::abs(v.z() - z_t) < 15 && v.y() < scene.chest_axis_y_mm)
        y = std::max(y, v.y());
    }
    return y;
  };
  // Between the wall's inner surface and the pericardium's front at x: their middle (or the wall plus
  // half the gap where the pericardium is not in front).
  auto between = [&](double x) {
    const double wall = x == 0 ? y_back : inner_wall(x);
    std::vector<SurfaceHit> front;
    scene.pericardium_grid.AllHits({x, wall, z_t}, {x, wall + 400, z_t}, &front);
    const double y = front.empty() ? wall + 0.5 * gap : 0.5 * (wall + front.front().point.y());
    return Eigen::Vector3d(x, y, z_t);
  };
  Eigen::Vector3d inner[2];
  for (int s = 0; s < 2; ++s) {
    Eigen::Vector3d inward(-ports[s].x(), scene.chest_axis_y_mm - ports[s].y(), 0);
    inner[s] = ports[s] + options.port_inset_mm * inward.normalized();
  }
  std::vector<Eigen::Vector3d> knots = {ports[0], inner[0]};
  for (double f : {0.7, 0.4}) knots.push_back(between(f * inner[0].x()));
  knots.push_back(between(0));
  for (double f : {0.4, 0.7}) knots.push_back(between(f * inner[1].x()));
  knots.insert(knots.end(), {inner[1], ports[1]});
  scene.tunnel.points = CatmullRom(knots, 2.0);
  // Where the curve between the knots cuts closer to the pericardium than half the gap, push it out.
  for (Eigen::Index i = 1; i + 1 < scene.tunnel.points.rows(); ++i) {
    Eigen::Vector3d p = scene.tunnel.points.row(i).transpose();
    SurfaceHit hit;
    if (scene.pericardium_grid.Nearest(p, 0.5 * gap, &hit) && hit.distance_mm > 0) {
      p += (0.5 * gap - hit.distance_mm) * (p - hit.point) / hit.distance_mm;
      scene.tunnel.points.row(i) = p.transpose();
    }
  }
  scene.tunnel.entry_port = ports[0];
  scene.tunnel.exit_port = ports[1];
  scene.tunnel.entry = spaces[0];
  scene.tunnel.exit = spaces[1];
  scene.tunnel.level_z_mm = z_t;
  for (Eigen::Index i = 0; i + 1 < scene.tunnel.points.rows(); ++i) {
    scene.tunnel.length_mm += (scene.tunnel.points.row(i + 1) - scene.tunnel.points.row(i)).norm();
  }

  // 5. One collision grid over every tissue the introducer meets.
  const std::pair<const TriangleMesh*, Organ> parts[] = {
      {&heart.mesh, kPericardium}, {&scene.right_lung.mesh, kLung}, {&scene.left_lung.mesh, kLung}};
  Eigen::Index nv = scene.bone_vertices.rows(), nf = scene.bone_faces.rows();
  for (const auto& [mesh, organ] : parts) nv += mesh->num_vertices(), nf += mesh->num_faces();
  scene.collision_vertices.resize(nv, 3);
  scene.collision_faces.resize(nf, 3);
  scene.collision_organ.resize(nf);
  scene.collision_vertices.topRows(scene.bone_vertices.rows()) = scene.bone_vertices;
  scene.collision_faces.topRows(scene.bone_faces.rows()) = scene.bone_faces;
  scene.collision_organ.head(scene.bone_faces.rows()).setConstant(kBone);
  Eigen::Index v0 = scene.bone_vertices.rows(), f0 = scene.bone_faces.rows();
  for (const auto& [mesh, organ] : parts) {
    scene.collision_vertices.middleRows(v0, mesh->num_vertices()) = mesh->vertices.positions;
    scene.collision_faces.middleRows(f0, mesh->num_faces()) =
        mesh->faces.array() + static_cast<std::int32_t>(v0);
    scene.collision_organ.segment(f0, mesh->num_faces()).setConstant(organ);
    v0 += mesh->num_vertices();
    f0 += mesh->num_faces();
  }
  scene.collision = TriangleGrid(scene.collision_vertices, scene.collision_faces, options.grid_cell_mm);
  return scene;
}

}  // namespace pectus::trainer
