#include "shape/model/measure_chest.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <unordered_map>
#include <vector>

#include "shape/core/error.h"

namespace pectus {
namespace {

// One transverse section: the segments (u0, w0, u1, w1) where the triangles cross the plane v = level.
struct Section {
  std::vector<Eigen::Vector4d> segments;
  int boundary_crossings = 0;
};

Section Cut(const TriangleMesh& mesh, const Points3& uvw, double level,
            const std::vector<std::pair<std::int32_t, std::int32_t>>& boundary) {
  Section s;
  for (Eigen::Index f = 0; f < mesh.num_faces(); ++f) {
    // A vertex on the plane counts as above it, so every crossing triangle gives exactly two points.
    double u[2], w[2];
    int found = 0;
    for (int e = 0; e < 3 && found < 2; ++e) {
      const auto a = uvw.row(mesh.faces(f, e)), b = uvw.row(mesh.faces(f, (e + 1) % 3));
      const double da = a(1) - level, db = b(1) - level;
      if ((da < 0.0) == (db < 0.0)) continue;
      const double t = da / (da - db);
      u[found] = a(0) + t * (b(0) - a(0));
      w[found] = a(2) + t * (b(2) - a(2));
      ++found;
    }
    if (found == 2) s.segments.emplace_back(u[0], w[0], u[1], w[1]);
  }
  for (const auto& [i, j] : boundary) {
    if ((uvw(i, 1) < level) != (uvw(j, 1) < level)) ++s.boundary_crossings;
  }
  return s;
}

// The front profile of a section: in each lateral bin, the most anterior point of the section polyline
// (its segments' ends in the bin and the segments crossing the bin's centre line), -inf for an empty bin.
std::vector<double> FrontProfile(const Section& s, double u0, double bin, int bins) {
  std::vector<double> top(static_cast<std::size_t>(bins), -std::numeric_limits<double>::infinity());
  auto put = [&](int b, double w) {
    if (b >= 0 && b < bins) top[b] = std::max(top[b], w);
  };
  for (const Eigen::Vector4d& g : s.segments) {
    put(static_cast<int>(std::floor((g[0] - u0) / bin)), g[1]);
    put(static_cast<int>(std::floor((g[2] - u0) / bin)), g[3]);
    const double lo = std::min(g[0], g[2]), hi = std::max(g[0], g[2]);
    if (!(hi > lo)) continue;
    const int first = std::max(0, static_cast<int>(std::ceil((lo - u0) / bin - 0.5)));
    const int last = std::min(bins - 1, static_cast<int>(std::floor((hi - u0) / bin - 0.5)));
    for (int b = first; b <= last; ++b) {
      const double uc = u0 + (b + 0.5) * bin;
      put(b, g[1] + (g[3] - g[1]) * (uc - g[0]) / (g[2] - g[0]));
    }
  }
  return top;
}

}  // namespace

bool ChestMeasuresOptions::IsValid(std::string* why) const {
  if (levels < 2 || !(bin_mm > 0.0) || !(lateral_reach_mm > 0.0) || !std::isfinite(bin_mm) ||
      !std::isfinite(lateral_reach_mm) || !(first_level_fraction >= 0.0 && first_level_fraction < 1.0)) {
    if (why != nullptr) {
      *why =
          "chest measures need >= 2 levels, a bin > 0 mm, a lateral reach > 0 mm and a first level in [0, 1)";
    }
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

ChestMeasures MeasureChest(const TriangleMesh& surface, const ChestRoi& roi,
                           const ChestMeasuresOptions& options, const std::string& what) {
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
    if (count == 1)
      boundary.emplace_back(static_cast<std::int32_t>(k >> 32), static_cast<std::int32_t>(k & 0xffffffffu));
  }

  const auto bins = static_cast<int>(std::ceil(2.0 * options.lateral_reach_mm / options.bin_mm));
  const double u0 = -options.lateral_reach_mm;
  ChestMeasures best;
  best.depression_depth_mm = -1.0;
  Section best_section;
  int levels_measured = 0;
  for (int l = 0; l < options.levels; ++l) {
    const double first = roi.v_min + options.first_level_fraction * roi.height();
    const double level = first + (roi.v_max - first) * static_cast<double>(l) / (options.levels - 1);
    Section s = Cut(surface, uvw, level, boundary);
    const std::vector<double> top = FrontProfile(s, u0, options.bin_mm, bins);
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
    ThrowBadInput(
        what, "no transverse section between the notch and the xiphoid reaches both sides of the midline");
  }
  best.depression_depth_mm = std::max(0.0, best.depression_depth_mm);

  // External indices at the deepest section, when it goes round the torso.
  best.closed_section = best_section.boundary_crossings == 0 && !best_section.segments.empty();
  if (best.closed_section) {
    double u_min = std::numeric_limits<double>::infinity(), u_max = -u_min, w_min = u_min, w_max = -u_min;
    for (const Eigen::Vector4d& g : best_section.segments) {
      u_min = std::min({u_min, g[0], g[2]});
      u_max = std::max({u_max, g[0], g[2]});
      w_min = std::min({w_min, g[1], g[3]});
      w_max = std::max({w_max, g[1], g[3]});
    }
    const double back = w_min;
    const double deepest = roi.ToRoi(best.deepest_point.transpose())(0, 2);
    best.chest_width_mm = u_max - u_min;
    best.ap_depth_min_mm = deepest - back;
    best.ap_depth_max_mm = w_max - back;
    if (best.ap_depth_min_mm > 0.0) best.external_haller_index = best.chest_width_mm / best.ap_depth_min_mm;
    if (best.ap_depth_max_mm > 0.0) {
      best.external_correction_index_pct =
          100.0 * (best.ap_depth_max_mm - best.ap_depth_min_mm) / best.ap_depth_max_mm;
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
