// Test helper: an analytic chest-like height field with a pectus-like depression, meshed finely and
// placed in an arbitrary frame, with its landmarks and exact depths for any ROI.
#pragma once

#include <Eigen/Geometry>
#include <cmath>

#include "shape/core/geometry.h"
#include "shape/core/landmarks.h"
#include "shape/model/compute_chest_roi.h"

namespace pectus::testing {

/// z = f(x, s) in the chest's own frame, the pectus frame (x to the subject's left, y up, z anterior; mm),
/// with s = -y the distance down the sternum: the point (x, -s, f(x, s)).
struct AnalyticChest {
  double radius = 160.0;     // transverse curvature radius
  double slope = 0.03;       // forward lean along the sternum
  double dent_depth = 15.0;  // Gaussian depression
  double dent_sigma = 25.0;
  double dent_y = 110.0;
  double dent_x = 0.0;        // lateral position of the depression's centre
  double groove_depth = 0.0;  // a groove along the sternum (x = 0), Gaussian across, constant along it
  double groove_sigma = 8.0;
  Similarity3 T_world_chest;  // where the chest sits in the test's "scanner" frame

  double f(double x, double s) const {
    return -x * x / (2.0 * radius) + slope * s -
           dent_depth * std::exp(-((x - dent_x) * (x - dent_x) + (s - dent_y) * (s - dent_y)) /
                                 (2.0 * dent_sigma * dent_sigma)) -
           groove_depth * std::exp(-x * x / (2.0 * groove_sigma * groove_sigma));
  }
  /// The point at (x, s) in the world frame.
  Eigen::Vector3d At(double x, double s) const { return T_world_chest * Eigen::Vector3d(x, -s, f(x, s)); }

  /// A triangle mesh over x in [x0, x1], s in [y0, y1] with `step` mm spacing, in the world frame.
  TriangleMesh Mesh(double x0, double x1, double y0, double y1, double step) const {
    const int nx = static_cast<int>(std::round((x1 - x0) / step)) + 1;
    const int ny = static_cast<int>(std::round((y1 - y0) / step)) + 1;
    TriangleMesh m;
    m.vertices.positions.resize(static_cast<Eigen::Index>(nx) * ny, 3);
    for (int j = 0; j < ny; ++j) {
      for (int i = 0; i < nx; ++i) {
        m.vertices.positions.row(static_cast<Eigen::Index>(j) * nx + i) =
            At(x0 + (x1 - x0) * i / (nx - 1), y0 + (y1 - y0) * j / (ny - 1)).transpose();
      }
    }
    m.faces.resize(2 * static_cast<Eigen::Index>(nx - 1) * (ny - 1), 3);
    Eigen::Index f = 0;
    for (int j = 0; j + 1 < ny; ++j) {
      for (int i = 0; i + 1 < nx; ++i) {
        const int a = j * nx + i, b = a + 1, c = a + nx, d = c + 1;
        // (a, c, b): x cross (-s) = x cross y = +z (anterior), counter-clockwise seen from the front.
        m.faces.row(f++) << a, c, b;
        m.faces.row(f++) << b, c, d;
      }
    }
    return m;
  }

  /// Landmarks on the surface: notch at s = 0, xiphoid at s = 180, cartilage at x = 45, s = 15.
  LandmarkSet Landmarks() const {
    LandmarkSet s;
    s.items.push_back({"sternal_notch", At(0.0, 0.0), ""});
    s.items.push_back({"xiphoid", At(0.0, 180.0), ""});
    s.items.push_back({"costal_cartilage_1_left", At(45.0, 15.0), ""});
    return s;
  }

  /// The exact depth w where the ROI normal through (u, v) meets the surface (Newton on the chest frame).
  double TrueDepth(const ChestRoi& roi, double u, double v) const {
    const Similarity3 T_chest_world = T_world_chest.Inverse();
    auto g = [&](double w) {
      const Eigen::Vector3d p = T_chest_world * roi.FromRoi(u, v, w);
      return p.z() - f(p.x(), -p.y());
    };
    double w = 0.0;
    for (int it = 0; it < 60; ++it) {
      const double h = 1e-4, gw = g(w), dg = (g(w + h) - g(w - h)) / (2 * h);
      const double step = gw / dg;
      w -= step;
      if (std::abs(step) < 1e-12) break;
    }
    return w;
  }
};

/// A chest placed at an arbitrary pose: rotated about a tilted axis and moved far from the origin.
inline AnalyticChest PlacedChest() {
  AnalyticChest c;
  c.T_world_chest.rotation =
      Eigen::AngleAxisd(0.7, Eigen::Vector3d(0.3, -1.0, 0.5).normalized()).toRotationMatrix();
  c.T_world_chest.translation = Eigen::Vector3d(1200.0, -350.0, 80.0);
  return c;
}

}  // namespace pectus::testing
