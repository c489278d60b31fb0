#include "planner_plugin/ribcage/ribcage_measurements.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>
#include <vector>

#include "shape/core/error.h"

namespace pectus::planner {
namespace {

struct SlicePoint {
  double x, y;
  int part;
};

// The faces binned by height (each in every bin of kBinMm its z-range overlaps, in index order), so that
// a slice visits only the faces near its level, not the whole surface, in the surface's own order (sums
// over them come out the same as over every face).
struct FacesByHeight {
  static constexpr double kBinMm = 2.0;
  double z0 = 0.0;                              // bottom of bin 0
  std::vector<std::vector<Eigen::Index>> bins;  // bins[k]: faces reaching into [z0 + k h, z0 + (k+1) h]
  const std::vector<Eigen::Index>& Straddling(double level) const {
    static const std::vector<Eigen::Index> kNone;
    const double k = std::floor((level - z0) / kBinMm);
    if (!(k >= 0 && k < static_cast<double>(bins.size()))) return kNone;
    return bins[static_cast<std::size_t>(k)];
  }
};

// Where the plane z = level cuts the surface: one segment (two points) per straddling triangle, oriented
// counter-clockwise (seen from above) around the section of the solid, so Green's theorem applies.
std::vector<SlicePoint> Slice(const RibcageSurface& s, const FacesByHeight& by_height, double level) {
  std::vector<SlicePoint> out;
  for (Eigen::Index f : by_height.Straddling(level)) {
    Eigen::Vector3d p[3];
    for (int i = 0; i < 3; ++i) p[i] = s.nodes.row(s.faces(f, i)).transpose();
    Eigen::Vector3d cut[2];
    int found = 0;
    for (int i = 0; i < 3 && found < 2; ++i) {
      const Eigen::Vector3d& a = p[i];
      const Eigen::Vector3d& b = p[(i + 1) % 3];
      if ((a.z() < level) == (b.z() < level)) continue;
      const double t = (level - a.z()) / (b.z() - a.z());
      cut[found++] = a + t * (b - a);
    }
    if (found < 2) continue;
    const Eigen::Vector3d normal = (p[1] - p[0]).cross(p[2] - p[0]);
    if (Eigen::Vector3d::UnitZ().cross(normal).dot(cut[1] - cut[0]) < 0) std::swap(cut[0], cut[1]);
    out.push_back({cut[0].x(), cut[0].y(), s.face_parts(f)});
    out.push_back({cut[1].x(), cut[1].y(), s.face_parts(f)});
  }
  return out;
}

struct SternumSection {
  bool found = false;
  double centre_x = 0, anterior_y = 0, posterior_y = 0, torsion_deg = 0;
};

// The sternum's section: area moments by Green's theorem over its oriented segments give the centroid
// and the principal (width) axis; the anterior and posterior surfaces are read across its middle.
SternumSection Sternum(const std::vector<SlicePoint>& points) {
  SternumSection s;
  double area = 0, mx = 0, my = 0, ixx = 0, iyy = 0, ixy = 0;  // ixx = integral y^2, iyy = integral x^2
  std::vector<Eigen::Vector2d> p;
  for (std::size_t k = 0; k + 1 < points.size(); k += 2) {
    if (points[k].part != 0) continue;
    const double x0 = points[k].x, y0 = points[k].y, x1 = points[k + 1].x, y1 = points[k + 1].y;
    const double cross = x0 * y1 - x1 * y0;
    area += cross / 2;
    mx += (x0 + x1) * cross / 6;
    my += (y0 + y1) * cross / 6;
    iyy += (x0 * x0 + x0 * x1 + x1 * x1) * cross / 12;
    ixx += (y0 * y0 + y0 * y1 + y1 * y1) * cross / 12;
    ixy += (x0 * y1 + 2 * x0 * y0 + 2 * x1 * y1 + x1 * y0) * cross / 24;
    p.emplace_back(x0, y0);
    p.emplace_back(x1, y1);
  }
  if (p.size() < 6 || !(area > 0)) return s;
  const Eigen::Vector2d mean(mx / area, my / area);
  const double cxx = iyy - area * mean.x() * mean.x(), cyy = ixx - area * mean.y() * mean.y();
  const double cxy = ixy - area * mean.x() * mean.y();
  // Major axis: the sternum's width direction on the slice.
  const double angle = 0.5 * std::atan2(2 * cxy, cxx - cyy);
  Eigen::Vector2d d(std::cos(angle), std::sin(angle));
  if (d.x() < 0) d = -d;
  s.torsion_deg = std::atan2(-d.y(), d.x()) * 180.0 / std::numbers::pi;
  double half_width = 0;
  for (const auto& q : p) half_width = std::max(half_width, std::abs((q - mean).dot(d)));
  s.anterior_y = std::numeric_limits<double>::infinity();
  s.posterior_y = -std::numeric_limits<double>::infinity();
  for (const auto& q : p) {
    if (std::abs((q - mean).dot(d)) > 0.25 * half_width) continue;
    s.anterior_y = std::min(s.anterior_y, q.y());
    s.posterior_y = std::max(s.posterior_y, q.y());
  }
  s.centre_x = mean.x();
  s.found = std::isfinite(s.anterior_y);
  return s;
}

double SpineY(const Points3& spine, double z) {
  for (Eigen::Index i = 1; i < spine.rows(); ++i) {
    const double z0 = spine(i - 1, 2), z1 = spine(i, 2);
    if ((z0 >= z && z >= z1) || (z0 <= z && z <= z1)) {
      const double t = z1 == z0 ? 0.0 : (z - z0) / (z1 - z0);
      return spine(i - 1, 1) + t * (spine(i, 1) - spine(i - 1, 1));
    }
  }
  ThrowBadInput("ribcage surface",
                "the spine line does not reach the measurement slice at z = " + std::to_string(z));
}

struct Setup {
  FacesByHeight faces;  // faces that reach into the search range
  double top = -std::numeric_limits<double>::infinity(), bottom = std::numeric_limits<double>::infinity();
};

Setup Prepare(const RibcageSurface& s, const RibcageMeasurementOptions& o) {
  std::string why;
  if (!o.IsValid(&why)) ThrowUsage("ribcage measurement options: " + why);
  if (s.face_parts.size() != s.faces.rows()) ThrowBadInput("ribcage surface", "one part per face is needed");
  Setup setup;
  for (Eigen::Index f = 0; f < s.faces.rows(); ++f) {
    if (s.face_parts(f) != 0) continue;
    for (int i = 0; i < 3; ++i) {
      setup.top = std::max(setup.top, s.nodes(s.faces(f, i), 2));
      setup.bottom = std::min(setup.bottom, s.nodes(s.faces(f, i), 2));
    }
  }
  if (!(setup.top > setup.bottom)) ThrowBadInput("ribcage surface", "no sternum faces (part 0) to measure");
  const double length = setup.top - setup.bottom;
  const double hi = setup.top - o.search_from * length + 1, lo = setup.top - o.search_to * length - 1;
  struct Reach {
    Eigen::Index face;
    double zmin, zmax;
  };
  std::vector<Reach> reach;
  for (Eigen::Index f = 0; f < s.faces.rows(); ++f) {
    double zmin = std::numeric_limits<double>::infinity(), zmax = -zmin;
    for (int i = 0; i < 3; ++i) {
      zmin = std::min(zmin, s.nodes(s.faces(f, i), 2));
      zmax = std::max(zmax, s.nodes(s.faces(f, i), 2));
    }
    if (zmax >= lo && zmin <= hi) reach.push_back({f, zmin, zmax});
  }
  // Bins over the faces' whole height range (a face straddles a level only within its own range).
  double z_lo = std::numeric_limits<double>::infinity(), z_hi = -z_lo;
  for (const Reach& r : reach) z_lo = std::min(z_lo, r.zmin), z_hi = std::max(z_hi, r.zmax);
  FacesByHeight& by_height = setup.faces;
  by_height.z0 = reach.empty() ? 0.0 : z_lo;
  by_height.bins.resize(reach.empty() ? 0
                                      : static_cast<std::size_t>((z_hi - z_lo) / FacesByHeight::kBinMm) + 1);
  for (const Reach& r : reach) {
    const auto first = static_cast<std::size_t>((r.zmin - z_lo) / FacesByHeight::kBinMm);
    const auto last = std::min(by_height.bins.size() - 1,
                               static_cast<std::size_t>((r.zmax - z_lo) / FacesByHeight::kBinMm));
    for (std::size_t k = first; k <= last; ++k) by_height.bins[k].push_back(r.face);
  }
  return setup;
}

// Depression on one slice, or NaN if the slice misses the sternum.
double SliceDepression(const std::vector<SlicePoint>& points, SternumSection* sternum) {
  *sternum = Sternum(points);
  if (!sternum->found) return std::numeric_limits<double>::quiet_NaN();
  double highest = std::numeric_limits<double>::infinity();
  for (const SlicePoint& q : points) highest = std::min(highest, q.y);
  return sternum->anterior_y - highest;
}

}  // namespace

bool RibcageMeasurementOptions::IsValid(std::string* why) const {
  if (!(slice_step_mm > 0 && slice_step_mm <= 10) || !(slice_softness_mm > 0 && slice_softness_mm <= 10)) {
    if (why) *why = "slice_step_mm and slice_softness_mm must be in (0, 10]";
    return false;
  }
  if (!(search_from >= 0 && search_from < search_to && search_to <= 1 && flat_level >= search_from &&
        flat_level <= search_to)) {
    if (why) *why = "need 0 <= search_from <= flat_level <= search_to <= 1 and search_from < search_to";
    return false;
  }
  return true;
}

std::string RibcageMeasurements::BriefReport() const {
  char line[400];
  std::snprintf(line, sizeof(line),
                "width %.2f mm, depth %.2f mm, sternal length %.2f mm, depression %.2f mm, torsion %.2f deg, "
                "Haller index %.2f (inner width %.1f mm / sternum-spine %.1f mm), slice at z = %.1f mm",
                width_mm, depth_mm, sternal_length_mm, depression_mm, torsion_deg, haller_index,
                inner_width_mm, sternum_to_spine_mm, slice_z_mm);
  return line;
}

std::vector<std::pair<double, double>> DepressionProfile(const RibcageSurface& surface,
                                                         const RibcageMeasurementOptions& options) {
  const Setup setup = Prepare(surface, options);
  const double length = setup.top - setup.bottom;
  std::vector<std::pair<double, double>> profile;
  for (double f = options.search_from; f <= options.search_to + 1e-9; f += options.slice_step_mm / length) {
    const double z = setup.top - f * length;
    SternumSection sternum;
    const double d = SliceDepression(Slice(surface, setup.faces, z), &sternum);
    if (std::isfinite(d)) profile.emplace_back(z, d);
  }
  return profile;
}

RibcageMeasurements MeasureRibcage(const RibcageSurface& surface, const RibcageMeasurementOptions& options) {
  const Setup setup = Prepare(surface, options);
  const double length = setup.top - setup.bottom;
  // The slice of deepest depression, as a soft maximum over the slice grid (levels weighted by
  // exp((depression - deepest) / tau)), so that it moves continuously with the ribcage when two levels
  // are nearly equally deep (the patient fit relies on it); among equal ones, the flat level wins.
  const double flat_z = setup.top - options.flat_level * length;
  const auto profile = DepressionProfile(surface, options);
  if (profile.empty()) ThrowBadInput("ribcage surface", "no axial slice cuts the sternum");
  double deepest = -std::numeric_limits<double>::infinity();
  std::vector<double> score;
  for (const auto& [z, depression] : profile) {
    score.push_back(depression - 1e-3 * std::abs(z - flat_z));
    deepest = std::max(deepest, score.back());
  }
  double weight_sum = 0, best_z = 0;
  for (std::size_t i = 0; i < profile.size(); ++i) {
    const double w = std::exp((score[i] - deepest) / options.slice_softness_mm);
    weight_sum += w;
    best_z += w * profile[i].first;
  }
  best_z /= weight_sum;
  const std::vector<SlicePoint> points = Slice(surface, setup.faces, best_z);
  SternumSection sternum;
  RibcageMeasurements m;
  m.depression_mm = SliceDepression(points, &sternum);
  m.slice_z_mm = best_z;
  m.notch_z_mm = setup.top;
  m.sternal_length_mm = length;
  m.torsion_deg = sternum.torsion_deg;
  double xmin = std::numeric_limits<double>::infinity(), xmax = -xmin, ymin = xmin, ymax = -xmin;
  const SlicePoint* left = nullptr;
  const SlicePoint* right = nullptr;
  for (const SlicePoint& q : points) {
    if (q.x > xmax) left = &q;
    if (q.x < xmin) right = &q;
    xmin = std::min(xmin, q.x);
    xmax = std::max(xmax, q.x);
    ymin = std::min(ymin, q.y);
    ymax = std::max(ymax, q.y);
  }
  m.width_mm = xmax - xmin;
  m.depth_mm = ymax - ymin;
  // Inner width: the inner surfaces of the rib sections that make the outer width (points of the same
  // rib within 20 mm of the extreme point: one crossing of the rib through the slice).
  double inner_left = left->x, inner_right = right->x;
  for (const SlicePoint& q : points) {
    if (q.part == left->part && std::hypot(q.x - left->x, q.y - left->y) < 20.0)
      inner_left = std::min(inner_left, q.x);
    if (q.part == right->part && std::hypot(q.x - right->x, q.y - right->y) < 20.0) {
      inner_right = std::max(inner_right, q.x);
    }
  }
  m.inner_width_mm = inner_left - inner_right;
  m.sternum_to_spine_mm = SpineY(surface.spine_anterior, best_z) - sternum.posterior_y;
  m.haller_index = m.sternum_to_spine_mm > 0 ? m.inner_width_mm / m.sternum_to_spine_mm
                                             : std::numeric_limits<double>::infinity();
  return m;
}

}  // namespace pectus::planner
