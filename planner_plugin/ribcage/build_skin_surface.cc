#include "planner_plugin/ribcage/build_skin_surface.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "planner_plugin/fem/tet_mesh.h"
#include "shape/core/error.h"

namespace pectus::planner {

bool SkinSurfaceOptions::IsValid(std::string* why) const {
  auto fail = [&](const std::string& reason) {
    if (why) *why = reason;
    return false;
  };
  if (!(soft_tissue_mm >= 0 && soft_tissue_mm <= 100)) return fail("soft_tissue_mm must be 0 to 100");
  if (!(half_angle_deg > 5 && half_angle_deg <= 120)) return fail("half_angle_deg must be 5 to 120");
  if (!(above_notch_mm >= 0 && below_xiphoid_mm >= 0)) return fail("the extents must not be negative");
  if (rows < 2 || columns < 2) return fail("rows and columns must be at least 2");
  if (!(reach_mm > 0 && reach_mm <= 50)) return fail("reach_mm must be in (0, 50]");
  return true;
}

Points3 SkinSurface::Deformed(const Points3& displacement) const {
  Points3 out = mesh.vertices.positions;
  for (std::size_t j = 0; j < ties.size(); ++j) {
    Eigen::RowVector3d u = Eigen::RowVector3d::Zero();
    for (const auto& [node, w] : ties[j]) u += w * displacement.row(node);
    out.row(static_cast<Eigen::Index>(j)) += u;
  }
  return out;
}

SkinSurface BuildSkinSurface(const PatientRibcage& ribcage, const SkinSurfaceOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) ThrowUsage("skin options: " + why);
  const Points3& x = ribcage.mesh.nodes;
  const MeshBoundary boundary = ExtractBoundary(ribcage.mesh);
  const double top = ribcage.measured.notch_z_mm + options.above_notch_mm;
  const double bottom =
      ribcage.measured.notch_z_mm - ribcage.measured.sternal_length_mm - options.below_xiphoid_mm;
  // The axis the rays leave from: midway between the sternum and the spine, per height. The spine of the
  // generic ribcage, scaled: a construction axis, not moved where the CT's Haller index places the
  // vertebral bodies (PatientRibcage::spine_shift_mm), so that the skin's rays stay as they were built.
  Points3 spine = ribcage.surface.spine_anterior;
  spine.col(1).array() -= ribcage.spine_shift_mm;
  auto axis_y = [&](double z) {
    double spine_y = spine(0, 1);
    for (Eigen::Index i = 1; i < spine.rows(); ++i) {
      if ((spine(i - 1, 2) - z) * (spine(i, 2) - z) <= 0 && spine(i - 1, 2) != spine(i, 2)) {
        const double t = (z - spine(i - 1, 2)) / (spine(i, 2) - spine(i - 1, 2));
        spine_y = spine(i - 1, 1) + t * (spine(i, 1) - spine(i - 1, 1));
        break;
      }
    }
    return 0.5 * spine_y;  // the sternum's front lies near y = 0 in the notch frame
  };
  // Bone boundary nodes in the anterior half, bucketed by height (1 mm buckets).
  const double reach = options.reach_mm, window = 3 * reach;
  const int buckets = static_cast<int>(std::ceil(top - bottom + 2 * window)) + 1;
  std::vector<std::vector<std::int32_t>> bucket(static_cast<std::size_t>(buckets));
  for (std::int32_t n : boundary.nodes) {
    const double z = x(n, 2);
    if (z > top + window || z < bottom - window) continue;
    if (x(n, 1) > axis_y(z)) continue;  // posterior half: never under the anterior skin
    bucket[static_cast<std::size_t>(
               std::clamp(static_cast<int>(std::floor(top + window - z)), 0, buckets - 1))]
        .push_back(n);
  }
  SkinSurface skin;
  skin.rows = options.rows;
  skin.columns = options.columns;
  skin.soft_tissue_mm = options.soft_tissue_mm;
  const Eigen::Index count = static_cast<Eigen::Index>(options.rows) * options.columns;
  skin.mesh.vertices.positions.resize(count, 3);
  skin.outward.resize(count, 3);
  skin.ties.resize(static_cast<std::size_t>(count));
  const double half_angle = options.half_angle_deg * std::numbers::pi / 180.0;
  for (int r = 0; r < options.rows; ++r) {
    const double z = top + (bottom - top) * r / (options.rows - 1);
    const double cy = axis_y(z);
    for (int c = 0; c < options.columns; ++c) {
      // Right (theta < 0, x < 0) to left across the front; theta = 0 straight ahead (-y).
      const double theta = -half_angle + 2 * half_angle * c / (options.columns - 1);
      const Eigen::Vector3d ray(std::sin(theta), -std::cos(theta), 0.0);
      const Eigen::Index j = static_cast<Eigen::Index>(r) * options.columns + c;
      // Bone nodes near the ray, weighted by their distance from it (a Gaussian of `reach`), the
      // outermost favoured (a soft maximum along the ray): the skin spans the gaps between ribs.
      std::vector<std::pair<std::int32_t, double>> near;
      double depth = 0;  // weighted distance of the bone along the ray
      for (double grow = 1.0; near.empty() && grow <= 16.0; grow *= 2.0) {
        const double w_reach = grow * reach, w_window = 3 * w_reach;
        std::vector<std::pair<std::int32_t, double>> candidates;  // node, distance along the ray
        double outermost = -std::numeric_limits<double>::infinity();
        const int b0 = std::clamp(static_cast<int>(std::floor(top + window - z - w_window)), 0, buckets - 1);
        const int b1 = std::clamp(static_cast<int>(std::floor(top + window - z + w_window)), 0, buckets - 1);
        for (int b = b0; b <= b1; ++b) {
          for (std::int32_t n : bucket[b]) {
            const Eigen::Vector3d p(x(n, 0), x(n, 1) - cy, x(n, 2) - z);
            const double along = p.x() * ray.x() + p.y() * ray.y();
            if (along <= 0) continue;
            const double across = p.x() * ray.y() - p.y() * ray.x();
            if (std::abs(across) > w_window || std::abs(p.z()) > w_window) continue;
            candidates.emplace_back(n, along);
            outermost = std::max(outermost, along);
          }
        }
        double sum = 0;
        for (const auto& [n, along] : candidates) {
          const Eigen::Vector3d p(x(n, 0), x(n, 1) - cy, x(n, 2) - z);
          const double across = p.x() * ray.y() - p.y() * ray.x();
          const double w = std::exp(-0.5 * (across * across + p.z() * p.z()) / (w_reach * w_reach) +
                                    (along - outermost) / 1.5);
          if (w < 1e-6) continue;
          near.emplace_back(n, w);
          sum += w;
        }
        for (auto& [n, w] : near) {
          w /= sum;
          const Eigen::Vector2d p(x(n, 0), x(n, 1) - cy);
          depth += w * (p.x() * ray.x() + p.y() * ray.y());
        }
      }
      if (near.empty()) {
        ThrowFailure("skin: no bone under the skin at z = " + std::to_string(z) + " mm, " +
                     std::to_string(theta * 180 / std::numbers::pi) + " degrees; reduce the skin's extent");
      }
      // The vertex stays on its ray (a height field over the grid): bone depth plus the soft tissue.
      skin.ties[static_cast<std::size_t>(j)] = std::move(near);
      skin.outward.row(j) = ray.transpose();
      skin.mesh.vertices.positions.row(j) =
          (Eigen::Vector3d(0.0, cy, z) + (depth + options.soft_tissue_mm) * ray).transpose();
    }
  }
  // Triangles: outward (counter-clockwise seen from in front of the chest).
  skin.mesh.faces.resize(2 * static_cast<Eigen::Index>(options.rows - 1) * (options.columns - 1), 3);
  Eigen::Index f = 0;
  for (int r = 0; r + 1 < options.rows; ++r) {
    for (int c = 0; c + 1 < options.columns; ++c) {
      const int a = r * options.columns + c, b = a + 1, d = a + options.columns, e = d + 1;
      skin.mesh.faces.row(f++) << a, d, b;
      skin.mesh.faces.row(f++) << b, d, e;
    }
  }
  // The landmarks: on the midline (between the two columns around theta = 0) at each bone landmark's
  // height, as bilinear weights of the four skin vertices around it.
  const double middle = 0.5 * (options.columns - 1);
  const int c0 = static_cast<int>(std::floor(middle)), c1 = std::min(c0 + 1, options.columns - 1);
  const double tc = middle - c0;
  const Points3& v = skin.mesh.vertices.positions;
  for (const Landmark& bone : ribcage.landmarks.items) {
    const double z = bone.position.z();
    SkinPoint point{bone.label, "skin over the " + bone.label, {}};
    for (int r = 0; r + 1 < options.rows && point.weights.empty(); ++r) {
      const Eigen::Index a0 = static_cast<Eigen::Index>(r) * options.columns + c0, a1 = a0 - c0 + c1;
      const Eigen::Index b0 = a0 + options.columns, b1 = a1 + options.columns;
      const double za = (1 - tc) * v(a0, 2) + tc * v(a1, 2), zb = (1 - tc) * v(b0, 2) + tc * v(b1, 2);
      if ((za - z) * (zb - z) > 0 || za == zb) continue;
      const double t = (z - za) / (zb - za);
      point.weights = {{a0, (1 - t) * (1 - tc)}, {a1, (1 - t) * tc}, {b0, t * (1 - tc)}, {b1, t * tc}};
    }
    if (point.weights.empty())
      ThrowFailure("skin landmarks: " + bone.label + " lies outside the skin's extent");
    skin.landmark_points.push_back(std::move(point));
  }
  return skin;
}

LandmarkSet SkinSurface::Landmarks(const Points3& positions) const {
  LandmarkSet out;
  for (const SkinPoint& point : landmark_points) {
    Eigen::Vector3d p = Eigen::Vector3d::Zero();
    for (const auto& [vertex, w] : point.weights) p += w * positions.row(vertex).transpose();
    out.items.push_back({point.label, p, point.description});
  }
  return out;
}

}  // namespace pectus::planner
