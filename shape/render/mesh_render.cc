// pectus: orthographic z-buffer rendering of triangle meshes and point clouds, Gouraud colours, Lambert
// shading with a headlight (two-sided, so open scans look right from either side).
#include "shape/render/mesh_render.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>

#include "shape/core/per_vertex_normals.h"

namespace pectus::render {
namespace {

// Screen mapping of an orthographic camera: pixel x, pixel y and depth of a world point.
struct Camera {
  Eigen::Vector3d right, up, forward;
  double scale = 1;       // pixels per mm
  double cx = 0, cy = 0;  // world centre projected on right / up (mm)
  int width = 0, height = 0;

  Eigen::Vector3d Project(const Eigen::Vector3d& p) const {
    return {width * 0.5 + (p.dot(right) - cx) * scale, height * 0.5 - (p.dot(up) - cy) * scale,
            p.dot(forward)};
  }
};

Camera MakeCamera(const View& view, const Points3& points) {
  Camera cam;
  cam.forward = view.direction.normalized();
  cam.right = cam.forward.cross(view.up);
  if (cam.right.norm() < 1e-9) cam.right = cam.forward.unitOrthogonal();
  cam.right.normalize();
  cam.up = cam.right.cross(cam.forward).normalized();
  cam.width = view.width;
  cam.height = view.height;
  Bounds3 b = view.frame ? *view.frame : ComputeBounds(points);
  if (b.empty()) b.min = b.max = Eigen::Vector3d::Zero();
  double r0 = std::numeric_limits<double>::infinity(), r1 = -r0, u0 = r0, u1 = -r0;
  for (int corner = 0; corner < 8; ++corner) {
    const Eigen::Vector3d c((corner & 1) ? b.max.x() : b.min.x(), (corner & 2) ? b.max.y() : b.min.y(),
                            (corner & 4) ? b.max.z() : b.min.z());
    r0 = std::min(r0, c.dot(cam.right));
    r1 = std::max(r1, c.dot(cam.right));
    u0 = std::min(u0, c.dot(cam.up));
    u1 = std::max(u1, c.dot(cam.up));
  }
  const double usable_w = view.width * (1 - 2 * view.margin), usable_h = view.height * (1 - 2 * view.margin);
  cam.scale = std::min(usable_w / std::max(r1 - r0, 1e-9), usable_h / std::max(u1 - u0, 1e-9));
  cam.cx = 0.5 * (r0 + r1);
  cam.cy = 0.5 * (u0 + u1);
  return cam;
}

Eigen::Vector3d ColourOf(const Colors3* colors, const PointCloud& cloud, Eigen::Index i, Rgb base) {
  const Colors3* c = colors != nullptr ? colors : (cloud.has_colors() ? &cloud.colors : nullptr);
  if (c == nullptr || i >= c->rows()) return {double(base.r), double(base.g), double(base.b)};
  return {double((*c)(i, 0)), double((*c)(i, 1)), double((*c)(i, 2))};
}

double Shade(const Eigen::Vector3d& normal, const Eigen::Vector3d& forward, bool shading) {
  if (!shading) return 1.0;
  const double n = normal.norm();
  if (!(n > 0)) return 0.75;
  return 0.3 + 0.7 * std::abs(normal.dot(forward)) / n;
}

Rgb ToRgb(const Eigen::Vector3d& c) {
  auto k = [](double v) { return static_cast<std::uint8_t>(std::clamp(std::lround(v), 0L, 255L)); };
  return {k(c.x()), k(c.y()), k(c.z())};
}

}  // namespace

View View::Front(int width, int height) {
  View v;
  v.direction = {0, 0, -1};
  v.up = {0, 1, 0};
  v.width = width;
  v.height = height;
  return v;
}

View View::Side(int width, int height) {
  View v = Front(width, height);
  v.direction = {-1, 0, 0};
  return v;
}

View View::Oblique(double yaw_deg, double pitch_deg, int width, int height) {
  View v = Front(width, height);
  const double kDeg = M_PI / 180.0;
  const Eigen::Matrix3d R = (Eigen::AngleAxisd(yaw_deg * kDeg, Eigen::Vector3d::UnitY()) *
                             Eigen::AngleAxisd(pitch_deg * kDeg, Eigen::Vector3d::UnitX()))
                                .toRotationMatrix();
  v.direction = R * v.direction;
  v.up = R * v.up;
  return v;
}

Image RenderMesh(const TriangleMesh& mesh, const View& view, const Colors3* colors) {
  Image image(view.width, view.height, view.background);
  const Points3& V = mesh.vertices.positions;
  if (V.rows() == 0) return image;
  const Camera cam = MakeCamera(view, V);
  // Meshes that carry no normals are shaded smoothly with area-weighted ones.
  const Points3 N = mesh.vertices.has_normals() ? mesh.vertices.normals : PerVertexNormals(V, mesh.faces);
  std::vector<Eigen::Vector3d> screen(static_cast<std::size_t>(V.rows()));
  std::vector<Eigen::Vector3d> lit(static_cast<std::size_t>(V.rows()));
  for (Eigen::Index i = 0; i < V.rows(); ++i) {
    screen[i] = cam.Project(V.row(i).transpose());
    lit[i] = ColourOf(colors, mesh.vertices, i, view.base_colour) *
             Shade(N.row(i).transpose(), cam.forward, view.shading);
  }
  std::vector<double> zbuf(static_cast<std::size_t>(view.width) * view.height,
                           std::numeric_limits<double>::infinity());
  for (Eigen::Index f = 0; f < mesh.num_faces(); ++f) {
    const Eigen::Vector3d& a = screen[mesh.faces(f, 0)];
    const Eigen::Vector3d& b = screen[mesh.faces(f, 1)];
    const Eigen::Vector3d& c = screen[mesh.faces(f, 2)];
    const double area = (b.x() - a.x()) * (c.y() - a.y()) - (b.y() - a.y()) * (c.x() - a.x());
    if (std::abs(area) < 1e-12) continue;
    const int x0 = std::max(0, static_cast<int>(std::floor(std::min({a.x(), b.x(), c.x()}))));
    const int x1 = std::min(view.width - 1, static_cast<int>(std::ceil(std::max({a.x(), b.x(), c.x()}))));
    const int y0 = std::max(0, static_cast<int>(std::floor(std::min({a.y(), b.y(), c.y()}))));
    const int y1 = std::min(view.height - 1, static_cast<int>(std::ceil(std::max({a.y(), b.y(), c.y()}))));
    for (int y = y0; y <= y1; ++y) {
      for (int x = x0; x <= x1; ++x) {
        const double px = x + 0.5, py = y + 0.5;
        const double w0 = ((b.x() - px) * (c.y() - py) - (b.y() - py) * (c.x() - px)) / area;
        const double w1 = ((c.x() - px) * (a.y() - py) - (c.y() - py) * (a.x() - px)) / area;
        const double w2 = 1 - w0 - w1;
        if (w0 < -1e-9 || w1 < -1e-9 || w2 < -1e-9) continue;
        const double z = w0 * a.z() + w1 * b.z() + w2 * c.z();
        double& zb = zbuf[static_cast<std::size_t>(y) * view.width + x];
        if (z >= zb) continue;
        zb = z;
        image.Set(
            x, y,
            ToRgb(w0 * lit[mesh.faces(f, 0)] + w1 * lit[mesh.faces(f, 1)] + w2 * lit[mesh.faces(f, 2)]));
      }
    }
  }
  return image;
}

Image RenderPoints(const PointCloud& cloud, const View& view, const Colors3* colors) {
  Image image(view.width, view.height, view.background);
  if (cloud.empty()) return image;
  const Camera cam = MakeCamera(view, cloud.positions);
  std::vector<double> zbuf(static_cast<std::size_t>(view.width) * view.height,
                           std::numeric_limits<double>::infinity());
  const int r = std::max(0, view.point_radius);
  // Without normals, depth cueing shows the shape: nearer points brighter.
  double z0 = std::numeric_limits<double>::infinity(), z1 = -z0;
  for (Eigen::Index i = 0; i < cloud.size(); ++i) {
    const double z = cloud.positions.row(i).dot(cam.forward);
    z0 = std::min(z0, z);
    z1 = std::max(z1, z);
  }
  for (Eigen::Index i = 0; i < cloud.size(); ++i) {
    const Eigen::Vector3d s = cam.Project(cloud.positions.row(i).transpose());
    double shade = 1.0;
    if (cloud.has_normals()) {
      shade = Shade(cloud.normals.row(i).transpose(), cam.forward, view.shading);
    } else if (view.shading && z1 > z0) {
      shade = 1.0 - 0.6 * (s.z() - z0) / (z1 - z0);
    }
    const Rgb c = ToRgb(ColourOf(colors, cloud, i, view.base_colour) * shade);
    // A point exactly on the far edge of the frame belongs to the last pixel, not beyond it.
    const int cx = std::min(static_cast<int>(std::floor(s.x())), view.width - 1);
    const int cy = std::min(static_cast<int>(std::floor(s.y())), view.height - 1);
    for (int dy = -r; dy <= r; ++dy) {
      for (int dx = -r; dx <= r; ++dx) {
        if (dx * dx + dy * dy > r * r + r) continue;
        const int x = cx + dx, y = cy + dy;
        if (x < 0 || y < 0 || x >= view.width || y >= view.height) continue;
        double& zb = zbuf[static_cast<std::size_t>(y) * view.width + x];
        if (s.z() >= zb) continue;
        zb = s.z();
        image.Set(x, y, c);
      }
    }
  }
  return image;
}

}  // namespace pectus::render
