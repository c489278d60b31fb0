#include "planner_plugin/trainer/god_object.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

#include "shape/core/error.h"
#include "shape/core/per_vertex_normals.h"

namespace pectus::trainer {
namespace {

// One constraint plane: n . x >= offset, from face `face`.
struct Plane {
  Eigen::Vector3d n;
  double offset;
  std::int32_t face;
};

// The point nearest `goal` on every plane of planes[0 .. count) (Ruspini et al. 1997: the Lagrange
// multipliers of the equality-constrained least squares, x = goal - sum lambda_i n_i). Planes that the goal
// does not press into (lambda_i > 0) are dropped from the set, newest first. Returns false if the planes are
// degenerate.
bool ProjectOntoPlanes(const Eigen::Vector3d& goal, Plane* planes, int* count, Eigen::Vector3d* x) noexcept {
  while (*count > 0) {
    const int k = *count;
    // G lambda = r with G = N N^T (k by k, padded with the identity to 3 by 3), r = N goal - offsets.
    Eigen::Matrix3d G = Eigen::Matrix3d::Identity();
    Eigen::Vector3d r = Eigen::Vector3d::Zero();
    for (int i = 0; i < k; ++i) {
      r(i) = planes[i].n.dot(goal) - planes[i].offset;
      for (int j = 0; j < k; ++j) G(i, j) = planes[i].n.dot(planes[j].n);
    }
    const Eigen::FullPivLU<Eigen::Matrix3d> lu(G);
    if (lu.rank() < 3) return false;
    const Eigen::Vector3d lambda = lu.solve(r);
    int drop = -1;
    for (int i = k - 1; i >= 0; --i) {
      if (lambda(i) > 0) {  // the goal lies in front of this plane: it holds nothing
        drop = i;
        break;
      }
    }
    if (drop < 0) {
      *x = goal;
      for (int i = 0; i < k; ++i) *x -= lambda(i) * planes[i].n;
      return true;
    }
    for (int i = drop; i + 1 < k; ++i) planes[i] = planes[i + 1];
    --*count;
  }
  *x = goal;
  return true;
}

}  // namespace

const std::array<Introducer, 3>& IntroducerSizes() {
  static const std::array<Introducer, 3> sizes = {
      {{"small", 6.0, 250.0}, {"medium", 8.0, 300.0}, {"large", 10.0, 350.0}}};
  return sizes;
}

bool ProxyOptions::IsValid(std::string* why) const {
  auto fail = [&](const char* m) {
    if (why != nullptr) *why = m;
    return false;
  };
  for (double k : stiffness_n_per_mm) {
    if (!(k > 0 && k < 100)) return fail("stiffness must be in (0, 100) N/mm");
  }
  if (!(static_friction >= 0 && dynamic_friction >= 0 && dynamic_friction <= static_friction))
    return fail("friction: 0 <= dynamic <= static");
  if (!(damping_n_s_per_mm >= 0)) return fail("damping must be >= 0");
  if (!(max_force_n > 0)) return fail("max_force_n must be > 0");
  if (!(surface_offset_mm > 0 && surface_offset_mm < 0.01))
    return fail("surface_offset_mm must be in (0, 0.01)");
  if (!(shaft_sample_spacing_mm > 0.5)) return fail("shaft_sample_spacing_mm must be > 0.5");
  if (!(shaft_collision_length_mm >= 0)) return fail("shaft_collision_length_mm must be >= 0");
  return true;
}

GodObject::GodObject(const TrainerScene& scene, const Introducer& introducer, const ProxyOptions& options)
    : scene_(&scene), introducer_(introducer), options_(options) {
  std::string why;
  if (!options.IsValid(&why)) ThrowUsage("haptic proxy: " + why);
  if (!(introducer.diameter_mm > 0 && introducer.shaft_length_mm > 0))
    ThrowUsage("haptic proxy: bad introducer");
  vertex_normals_ = PerVertexNormals(scene.collision_vertices, scene.collision_faces);
}

void GodObject::Reset(const Eigen::Vector3d& tip_mm) {
  contact_ = ProxyContact{};
  contact_.proxy_mm = contact_.goal_mm = tip_mm;
  last_depth_mm_ = 0;
}

Eigen::Vector3d GodObject::Slide(const Eigen::Vector3d& from, const Eigen::Vector3d& target,
                                 ProxyContact* c) const noexcept {
  const TriangleGrid& grid = scene_->collision;
  const double eps = options_.surface_offset_mm;
  Plane planes[3];
  int count = 0;
  std::int32_t ignore[3];
  Eigen::Vector3d p = from;
  for (int iteration = 0; iteration < 8; ++iteration) {
    Eigen::Vector3d x;
    if (!ProjectOntoPlanes(target, planes, &count, &x)) break;  // degenerate corner: stay
    for (int i = 0; i < count; ++i) ignore[i] = planes[i].face;
    SurfaceHit hit;
    if (!grid.FirstHit(p, x, ignore, count, &hit)) {
      p = x;
      break;
    }
    p = hit.point + eps * hit.normal;  // on the surface, a hair in front
    const Plane plane{hit.normal, hit.normal.dot(hit.point) + eps, hit.face};
    int same = -1;  // a neighbour of nearly the same plane replaces it (a degenerate set otherwise)
    for (int i = 0; i < count; ++i) {
      if (planes[i].n.dot(plane.n) > 0.9999) same = i;
    }
    if (same >= 0) {
      planes[same] = plane;
      continue;
    }
    if (count == 3) break;  // held by three planes: a vertex of the constraints
    planes[count++] = plane;
  }
  c->num_planes = count;
  for (int i = 0; i < 3; ++i) c->faces[i] = i < count ? planes[i].face : -1;
  return p;
}

const ProxyContact& GodObject::Update(const Eigen::Vector3d& tip_mm, const Eigen::Quaterniond& orientation,
                                      double dt_s) noexcept {
  if (!tip_mm.allFinite() || !orientation.coeffs().allFinite() || !(dt_s >= 0)) {
    contact_.force_n.setZero();  // a bad reading renders nothing and leaves the proxy where it was
    contact_.torque_nmm.setZero();
    return contact_;
  }
  const Eigen::Vector3d previous = contact_.proxy_mm;
  const bool was_touching = contact_.num_planes > 0;
  ProxyContact c;
  c.goal_mm = tip_mm;
  // 1. The frictionless proxy: from where it was towards the tip, along the surfaces.
  Eigen::Vector3d proxy = Slide(previous, tip_mm, &c);
  // 2. Friction (a cone about the contact normal): stick while the tip's tangential offset from the
  //    old proxy is within mu_s of its depth; else slide, keeping mu_d of the depth as tangential lag.
  if (was_touching && c.num_planes > 0) {
    const Eigen::Vector3d n = scene_->collision.face_normals().row(c.faces[0]);
    const Eigen::Vector3d d = tip_mm - previous;
    const double depth = std::max(0.0, -d.dot(n));
    const Eigen::Vector3d tangential = d + depth * n;
    const double t_len = tangential.norm();
    if (t_len <= options_.static_friction * depth) {
      ProxyContact held = c;
      proxy = Slide(previous, previous, &held);  // stays; keeps the planes
      c.stuck = true;
    } else if (t_len > 0 && options_.dynamic_friction > 0) {
      const Eigen::Vector3d lag = (options_.dynamic_friction * depth / t_len) * tangential;
      ProxyContact slid = c;
      proxy = Slide(previous, proxy - lag, &slid);
      if (slid.num_planes > 0) c = slid, c.goal_mm = tip_mm;
    }
  }
  c.proxy_mm = proxy;
  // 3. The force: F = -k x (Eq. 15), k the stiffest touched tissue; the normal part along the shaded
  //    normal with one plane; a damper on the depth's rate; never pulling into the surface.
  Eigen::Vector3d force = Eigen::Vector3d::Zero();
  double depth = 0;
  if (c.num_planes > 0) {
    double k = 0;
    for (int i = 0; i < c.num_planes; ++i) {
      const int organ = scene_->collision_organ(c.faces[i]);
      k = std::max(k, options_.stiffness_n_per_mm[static_cast<std::size_t>(organ)]);
      c.organs_touched |= 1u << organ;
    }
    const Eigen::Vector3d x = tip_mm - proxy;
    const Eigen::Vector3d n_face = scene_->collision.face_normals().row(c.faces[0]);
    Eigen::Vector3d n = n_face;
    if (options_.force_shading && c.num_planes == 1) {
      const auto f = scene_->collision.faces().row(c.faces[0]);
      const Eigen::Vector3d a = scene_->collision_vertices.row(f(0)),
                            b = scene_->collision_vertices.row(f(1)),
                            cc = scene_->collision_vertices.row(f(2));
      const Eigen::Vector3d area = (b - a).cross(cc - a);
      const double area2 = area.squaredNorm();
      if (area2 > 0) {
        const double wa = (b - proxy).cross(cc - proxy).dot(area) / area2;
        const double wb = (cc - proxy).cross(a - proxy).dot(area) / area2;
        const Eigen::Vector3d shaded = wa * vertex_normals_.row(f(0)) + wb * vertex_normals_.row(f(1)) +
                                       (1 - wa - wb) * vertex_normals_.row(f(2));
        if (shaded.squaredNorm() > 1e-12 && shaded.dot(n_face) > 0.5) n = shaded.normalized();
      }
    }
    depth = std::max(0.0, -x.dot(n_face));
    force = -k * ((x + depth * n_face) - depth * n);  // tangential spring, normal along the shaded normal
    if (dt_s > 0) force += options_.damping_n_s_per_mm * ((depth - last_depth_mm_) / dt_s) * n;
    const double normal = force.dot(n);
    if (normal < 0) force -= normal * n;
    if (c.organs_touched & (1u << kPericardium)) c.pericardium_force_n += force.norm();
  }
  last_depth_mm_ = depth;
  // 4. The shaft: a capsule of the introducer's radius behind the tip, penalty forces where it enters.
  const Eigen::Vector3d axis = orientation * Eigen::Vector3d::UnitZ();
  const double radius = 0.5 * introducer_.diameter_mm;
  const double reach = std::min(options_.shaft_collision_length_mm, introducer_.shaft_length_mm);
  for (double s = options_.shaft_sample_spacing_mm; s <= reach; s += options_.shaft_sample_spacing_mm) {
    const Eigen::Vector3d centre = tip_mm - s * axis;
    SurfaceHit hit;
    if (!scene_->collision.Nearest(centre, radius, &hit)) continue;
    const Eigen::Vector3d away = centre - hit.point;
    const bool outside = away.dot(hit.normal) >= 0;
    const double penetration = outside ? radius - hit.distance_mm : radius + hit.distance_mm;
    const Eigen::Vector3d dir =
        outside && hit.distance_mm > 1e-9 ? Eigen::Vector3d(away / hit.distance_mm) : hit.normal;
    const int organ = scene_->collision_organ(hit.face);
    const Eigen::Vector3d f =
        options_.stiffness_n_per_mm[static_cast<std::size_t>(organ)] * penetration * dir;
    force += f;
    c.torque_nmm += (centre - tip_mm).cross(f);
    c.organs_touched |= 1u << organ;
    if (organ == kPericardium) c.pericardium_force_n += f.norm();
  }
  // 5. Within what the device can render.
  const double magnitude = force.norm();
  if (magnitude > options_.max_force_n) force *= options_.max_force_n / magnitude;
  c.force_n = force;
  contact_ = c;
  return contact_;
}

}  // namespace pectus::trainer
