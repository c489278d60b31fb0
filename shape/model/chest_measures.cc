#include "shape/model/chest_measures.h"

#include <cmath>
#include <limits>
#include <sstream>
#include <unordered_map>
#include <vector>

#include "shape/core/error.h"

namespace pectus {
namespace {

// One transverse section: the crossing points (u, w) of the triangles with the plane v = level.
struct Section {
  std::vector<double> u, w;
  int boundary_crossings = 0;
};

Section Cut(const TriangleMesh& mesh, const Points3& uvw, double level,
            const std::vector<std::pair<std::int32_t, std::int32_t>>& boundary) {
  Section s;
  for (Eigen::Index f = 0; f < mesh.num_faces(); ++f) {
    for (int e = 0; e < 3; ++e) {
      const auto a = uvw.row(mesh.faces(f, e)), b = uvw.row(mesh.faces(f, (e + 1) % 3));
      const double da = a(1) - level, db = b(1) - level;
      if ((da < 0.0) == (db < 0.0)) continue;
      const double t = da / (da - db);
      s.u.push_back(a(0) + t * (b(0) - a(0)));
      s.w.push_back(a(2) + t * (b(2) - a(2)));
    }
  }
  for (const auto& [i, j] : boundary) {
    if ((uvw(i, 1) < level) != (uvw(j, 1) < level)) ++s.boundary_crossings;
  }
  return s;
}

}  // namespace

bool ChestMeasuresOptions::IsValid(std::string* why) const {
  if (levels < 2 || !(bin_mm > 0.0) || !(lateral_reach_mm > 0.0) || !std::isfinite(bin_mm) ||
      !std::isfinite(lateral_reach_mm)) {
    if (why != nullptr) *why = "chest measures need >= 2 levels, a bin > 0 mm and a lateral reach > 0 mm";
    return false;
  }
  return true;
}

nlohmann::json ChestMeasures::ToJson() const {
  auto num = [](double x) { return std::isfinite(x) ? nlohmann::json(x) : nlohmann::json(nullptr); };
  return {{"depression_depth_mm", depression_depth_mm},
          {"depression_level_mm", depression_level_mm},
          {"depression_lateral_mm", depression_lateral_mm},
          {"deepest_point_mm", {deepest_point.x(), deepest_point.y(), deepest_point.z()}},
          {"closed_section", closed_section},
          {"chest_width_mm", num(chest_width_mm)},
          {"ap_depth_min_mm", num(ap_depth_min_mm)},
          {"ap_depth_max_mm", num(ap_depth_max_mm)},
          {"external_haller_index", num(external_haller_index)},
          {"external_correction_index_pct", num(external_correction_index_pct)}};
}

ChestMeasures MeasureChest(const TriangleMesh& surface, const ChestRoi& roi, const ChestMeasuresOptions& options,
                           const std::string& what) {
  std::string why;
  if (!options.IsValid(&why)) ThrowUsage(why);
  surface.Validate(what);
  if (surface.num_faces() == 0) ThrowBadInput(what, "has no triangles; chest measures need a surface mesh");
  const Points3 uvw = roi.ToRoi(surface.vertices.positions);

  // Boundary edges (used by one face) tell an open section (a frontal scan) from a closed one (a torso).
  std::unordered_map<std::uint64_t, int> edge_count;
  auto key = [](std::int32_t a, std::int32_t b) {
    return (static_cast<std::uint64_t>(std::min(a, b)) << 32) | static_cast<std::uint32_t>(std::max(a, b));
  };
  for (Eigen::Index f = 0; f < surface.num_faces(); ++f) {
    for (int e = 0; e < 3; ++e) ++edge_count[key(surface.faces(f, e), surface.faces(f, (e + 1) % 3))];
  }
  std::vector<std::pair<std::int32_t, std::int32_t>> boundary;
  for (const auto& [k, count] : edge_count) {
    if (count == 1) boundary.emplace_back(static_cast<std::int32_t>(k >> 32), static_cast<std::int32_t>(k & 0xffffffffu));
  }

  const auto bins = static_cast<int>(std::ceil(2.0 * options.lateral_reach_mm / options.bin_mm));
  const double u0 = -options.lateral_reach_mm;
  ChestMeasures best;
  best.depression_depth_mm = -1.0;
  Section best_section;
  int levels_measured = 0;
  for (int l = 0; l < options.levels; ++l) {
    const double level = roi.v_min + roi.height() * static_cast<double>(l) / (options.levels - 1);
    Section s = Cut(surface, uvw, level, boundary);
    // Front profile: the most anterior skin point in each lateral bin.
    std::vector<double> top(static_cast<std::size_t>(bins), -std::numeric_limits<double>::infinity());
    for (std::size_t k = 0; k < s.u.size(); ++k) {
      const int b = static_cast<int>(std::floor((s.u[k] - u0) / options.bin_mm));
      if (b >= 0 && b < bins) top[b] = std::max(top[b], s.w[k]);
    }
    // The straight edge rests on the highest point on each side of the midline.
    int left = -1, right = -1;
    for (int b = 0; b < bins; ++b) {
      if (!std::isfinite(top[b])) continue;
      const double u = u0 + (b + 0.5) * options.bin_mm;
      if (u >= 0.0 && (left < 0 || top[b] > top[left])) left = b;
      if (u < 0.0 && (right < 0 || top[b] > top[right])) right = b;
    }
    if (left < 0 || right < 0) continue;
    ++levels_measured;
    const double ur = u0 + (right + 0.5) * options.bin_mm, ul = u0 + (left + 0.5) * options.bin_mm;
    for (int b = right; b <= left; ++b) {
      if (!std::isfinite(top[b])) continue;
      const double u = u0 + (b + 0.5) * options.bin_mm;
      const double edge = top[right] + (top[left] - top[right]) * (u - ur) / (ul - ur);
      const double gap = edge - top[b];
      if (gap > best.depression_depth_mm) {
        best.depression_depth_mm = gap;
        best.depression_level_mm = level;
        best.depression_lateral_mm = u;
        best.deepest_point = roi.FromRoi(u, level, top[b]);
        best_section = s;
      }
    }
  }
  if (levels_measured == 0) {
    ThrowBadInput(what, "no transverse section between the notch and the xiphoid reaches both sides of the midline");
  }
  best.depression_depth_mm = std::max(0.0, best.depression_depth_mm);

  // External indices at the deepest section, when it goes round the torso.
  best.closed_section = best_section.boundary_crossings == 0 && !best_section.u.empty();
  if (best.closed_section) {
    const Eigen::Map<const Eigen::VectorXd> u(best_section.u.data(), static_cast<Eigen::Index>(best_section.u.size()));
    const Eigen::Map<const Eigen::VectorXd> w(best_section.w.data(), static_cast<Eigen::Index>(best_section.w.size()));
    const double back = w.minCoeff();
    const double deepest = roi.ToRoi(best.deepest_point.transpose())(0, 2);
    best.chest_width_mm = u.maxCoeff() - u.minCoeff();
    best.ap_depth_min_mm = deepest - back;
    best.ap_depth_max_mm = w.maxCoeff() - back;
    if (best.ap_depth_min_mm > 0.0) best.external_haller_index = best.chest_width_mm / best.ap_depth_min_mm;
    if (best.ap_depth_max_mm > 0.0) {
      best.external_correction_index_pct = 100.0 * (best.ap_depth_max_mm - best.ap_depth_min_mm) / best.ap_depth_max_mm;
    }
  }
  std::ostringstream msg;
  msg << "depression " << best.depression_depth_mm << " mm deep at " << best.depression_level_mm
      << " mm below the notch";
  if (best.closed_section) {
    msg << "; external Haller index " << best.external_haller_index << ", external correction index "
        << best.external_correction_index_pct << " %";
  } else {
    msg << "; the surface does not go round the torso there, so no external indices";
  }
  best.message = msg.str();
  return best;
}

}  // namespace pectus
