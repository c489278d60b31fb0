#include "shape/model/cross_section_resampler.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include "shape/core/error.h"

namespace pectus {
namespace {

// The points of one section profile: abscissa t along the section, depth y (mm).
struct Profile {
  std::vector<double> t, y;
};

// Keeps, in each bin of width `bin` along t, only the points within `depth` of the most anterior one.
void KeepFrontEnvelope(double bin, double depth, Profile* p) {
  if (p->t.empty()) return;
  const double t0 = *std::min_element(p->t.begin(), p->t.end());
  const double t1 = *std::max_element(p->t.begin(), p->t.end());
  const auto bins = static_cast<std::size_t>((t1 - t0) / bin) + 1;
  std::vector<double> top(bins, -std::numeric_limits<double>::infinity());
  auto bin_of = [&](double t) { return std::min(bins - 1, static_cast<std::size_t>((t - t0) / bin)); };
  for (std::size_t k = 0; k < p->t.size(); ++k)
    top[bin_of(p->t[k])] = std::max(top[bin_of(p->t[k])], p->y[k]);
  std::size_t kept = 0;
  for (std::size_t k = 0; k < p->t.size(); ++k) {
    if (p->y[k] >= top[bin_of(p->t[k])] - depth) {
      p->t[kept] = p->t[k];
      p->y[kept] = p->y[k];
      ++kept;
    }
  }
  p->t.resize(kept);
  p->y.resize(kept);
}

// Cuts a triangle (ROI coordinates) with the plane coordinate[axis] == level; appends the crossing points
// (coordinate[other], w) whose abscissa lies in [lo, hi].
void CutTriangle(const Eigen::Vector3d* p, int axis, int other, double level, double lo, double hi,
                 Profile* out) {
  for (int e = 0; e < 3; ++e) {
    const Eigen::Vector3d& a = p[e];
    const Eigen::Vector3d& b = p[(e + 1) % 3];
    const double da = a[axis] - level, db = b[axis] - level;
    Eigen::Vector3d x;
    if (da == 0.0) {
      x = a;
    } else if ((da < 0.0 && db > 0.0) || (da > 0.0 && db < 0.0)) {
      x = a + (da / (da - db)) * (b - a);
    } else {
      continue;
    }
    if (x[other] < lo || x[other] > hi) continue;
    out->t.push_back(x[other]);
    out->y.push_back(x[2]);
  }
}

// Indices k with positions[k] in [lo, hi], positions equally spaced: [first, last] (empty if first > last).
std::pair<int, int> IndexRange(const Eigen::VectorXd& positions, double lo, double hi) {
  const double p0 = positions[0];
  const double step = (positions[positions.size() - 1] - p0) / static_cast<double>(positions.size() - 1);
  const int n = static_cast<int>(positions.size());
  const int first = std::max(0, static_cast<int>(std::ceil((lo - p0) / step - 1e-9)));
  const int last = std::min(n - 1, static_cast<int>(std::floor((hi - p0) / step + 1e-9)));
  return {first, last};
}

// How irregular each family of profiles is: the mean squared third and fourth derivatives of its curves
// (mm^-4, mm^-6) at the grid positions on data, by differences `h` (mm) apart. A cubic P-spline with a
// third-order penalty continues a curve past the data with an error of about |d3w| g^3 / 6 at a distance g,
// and bridges a hole from data at distances a below and b above with about |d4w| (a b)^2 / 24.
struct Roughness {
  double d3 = 0.0, d4 = 0.0;
};
Roughness FamilyRoughness(const std::vector<ProfileCurve>& curves, const Eigen::VectorXd& t, double h) {
  Roughness r;
  Eigen::Index count = 0;
  for (const ProfileCurve& c : curves) {
    if (!c.valid()) continue;
    for (Eigen::Index a = 0; a < t.size(); ++a) {
      const double x = t[a];
      if (c.DistanceToData(x - 2.0 * h) > h || c.DistanceToData(x + 2.0 * h) > h) continue;
      const double m2 = c(x - 2.0 * h), m1 = c(x - h), z = c(x), p1 = c(x + h), p2 = c(x + 2.0 * h);
      const double d3 = (p2 - 2.0 * p1 + 2.0 * m1 - m2) / (2.0 * h * h * h);
      const double d4 = (p2 - 4.0 * p1 + 6.0 * z - 4.0 * m1 + m2) / (h * h * h * h);
      r.d3 += d3 * d3;
      r.d4 += d4 * d4;
      ++count;
    }
  }
  if (count > 0) r.d3 /= static_cast<double>(count), r.d4 /= static_cast<double>(count);
  return r;
}

// Expected squared error (mm^2) of curve `c` at t beyond its fit residual (see FamilyRoughness).
double BridgingErrorSquared(const ProfileCurve& c, double t, const Roughness& r) {
  double below = 0.0, above = 0.0;
  c.DistancesToDataOnEachSide(t, &below, &above);
  if (std::isfinite(below) && std::isfinite(above)) return r.d4 * std::pow(below * above, 4) / 576.0;
  const double g = std::min(below, above);
  return r.d3 * std::pow(g, 6) / 36.0;
}

}  // namespace

SectionDirections ParseSectionDirections(const std::string& text) {
  if (text == "rows") return SectionDirections::kRows;
  if (text == "columns") return SectionDirections::kColumns;
  if (text == "both") return SectionDirections::kBoth;
  ThrowUsage("section directions '" + text + "' are not 'rows', 'columns' or 'both'");
}

std::string ToString(SectionDirections directions) {
  switch (directions) {
    case SectionDirections::kRows: return "rows";
    case SectionDirections::kColumns: return "columns";
    case SectionDirections::kBoth: return "both";
  }
  return "both";
}

bool CrossSectionOptions::IsValid(std::string* why) const {
  auto fail = [&](const std::string& m) {
    if (why != nullptr) *why = m;
    return false;
  };
  if (!grid.IsValid(why) || !fit.IsValid(why)) return false;
  if (!(fit_margin_mm >= 0.0) || !std::isfinite(fit_margin_mm)) return fail("fit margin must be >= 0 mm");
  if (!(slab_half_width_mm > 0.0) || !std::isfinite(slab_half_width_mm))
    return fail("slab half-width must be > 0 mm");
  if (!(envelope_bin_mm > 0.0) || !(envelope_depth_mm > 0.0) || !std::isfinite(envelope_bin_mm) ||
      !std::isfinite(envelope_depth_mm)) {
    return fail("front envelope bin and depth must be > 0 mm");
  }
  if (min_profile_points < 2) return fail("a profile needs at least 2 points");
  return holes.IsValid(why);
}

CrossSectionResult ResampleCrossSections(const TriangleMesh& surface, const ChestRoi& roi,
                                         const CrossSectionOptions& options, const std::string& what) {
  std::string why;
  if (!options.IsValid(&why)) ThrowUsage(why);
  surface.Validate(what);
  const GridSize& grid = options.grid;
  const Eigen::VectorXd u = GridLateralPositions(roi, grid);
  const Eigen::VectorXd v = GridSternalPositions(roi, grid);
  const double margin = options.fit_margin_mm;
  const bool use_rows = options.directions != SectionDirections::kColumns;
  const bool use_columns = options.directions != SectionDirections::kRows;

  // 1. Every point in ROI coordinates (u, v, w).
  const Points3 uvw = roi.ToRoi(surface.vertices.positions);

  // 2. Section profiles: rows cut at v = v_i give depth(u); columns cut at u = u_j give depth(v).
  std::vector<Profile> rows(use_rows ? grid.sternal : 0), columns(use_columns ? grid.lateral : 0);
  const double u_lo = roi.u_min - margin, u_hi = roi.u_max + margin;
  const double v_lo = roi.v_min - margin, v_hi = roi.v_max + margin;
  if (surface.num_faces() > 0) {
    Eigen::Vector3d p[3];
    for (Eigen::Index f = 0; f < surface.num_faces(); ++f) {
      for (int c = 0; c < 3; ++c) p[c] = uvw.row(surface.faces(f, c)).transpose();
      const Eigen::Vector3d lo = p[0].cwiseMin(p[1]).cwiseMin(p[2]);
      const Eigen::Vector3d hi = p[0].cwiseMax(p[1]).cwiseMax(p[2]);
      if (hi.x() < u_lo || lo.x() > u_hi || hi.y() < v_lo || lo.y() > v_hi) continue;
      if (use_rows) {
        const auto [first, last] = IndexRange(v, lo.y(), hi.y());
        for (int i = first; i <= last; ++i) CutTriangle(p, 1, 0, v[i], u_lo, u_hi, &rows[i]);
      }
      if (use_columns) {
        const auto [first, last] = IndexRange(u, lo.x(), hi.x());
        for (int j = first; j <= last; ++j) CutTriangle(p, 0, 1, u[j], v_lo, v_hi, &columns[j]);
      }
    }
  } else {
    const double h = options.slab_half_width_mm;
    for (Eigen::Index k = 0; k < uvw.rows(); ++k) {
      const double pu = uvw(k, 0), pv = uvw(k, 1), pw = uvw(k, 2);
      if (pu < u_lo || pu > u_hi || pv < v_lo || pv > v_hi) continue;
      if (use_rows) {
        const auto [first, last] = IndexRange(v, pv - h, pv + h);
        for (int i = first; i <= last; ++i) rows[i].t.push_back(pu), rows[i].y.push_back(pw);
      }
      if (use_columns) {
        const auto [first, last] = IndexRange(u, pu - h, pu + h);
        for (int j = first; j <= last; ++j) columns[j].t.push_back(pv), columns[j].y.push_back(pw);
      }
    }
  }

  // 3. A curve through each profile's front envelope.
  std::vector<ProfileCurve> row_curves(rows.size()), column_curves(columns.size());
  auto fit_all = [&](std::vector<Profile>& profiles, std::vector<ProfileCurve>& curves, double lo,
                     double hi) {
#pragma omp parallel for schedule(dynamic)
    for (std::size_t k = 0; k < profiles.size(); ++k) {
      KeepFrontEnvelope(options.envelope_bin_mm, options.envelope_depth_mm, &profiles[k]);
      if (static_cast<int>(profiles[k].t.size()) < options.min_profile_points) continue;
      const Eigen::Map<const Eigen::VectorXd> t(profiles[k].t.data(),
                                                static_cast<Eigen::Index>(profiles[k].t.size()));
      const Eigen::Map<const Eigen::VectorXd> y(profiles[k].y.data(),
                                                static_cast<Eigen::Index>(profiles[k].y.size()));
      curves[k] = FitProfile(t, y, lo, hi, options.fit);
    }
  };
  fit_all(rows, row_curves, roi.u_min, roi.u_max);
  fit_all(columns, column_curves, roi.v_min, roi.v_max);

  CrossSectionResult result;
  result.roi = roi;
  result.grid = grid;
  double sum_sq = 0.0;
  for (const auto* curves : {&row_curves, &column_curves}) {
    for (const ProfileCurve& c : *curves) {
      if (c.valid()) {
        ++result.profiles_fitted;
        result.profile_points += c.num_points();
        sum_sq += c.rms_residual() * c.rms_residual() * static_cast<double>(c.num_points());
      } else {
        ++result.profiles_unfitted;
      }
    }
  }
  result.fit_rms_mm =
      result.profile_points > 0 ? std::sqrt(sum_sq / static_cast<double>(result.profile_points)) : 0.0;

  // 4. Sample the curves at the grid; where both a row and a column pass through a vertex, blend them by
  //    the inverse of each one's expected squared error there: the fit's own noise plus the error of
  //    bridging the hole or continuing past the data (BridgingErrorSquared, with the derivatives typical of
  //    its family). So a vertex on data in one direction takes that direction, and inside a hole the
  //    direction along which the chest bends less regularly (a groove along the sternum seen across it)
  //    gives way.
  const double h = options.fit.knot_spacing_mm;
  const Roughness row_roughness = use_rows ? FamilyRoughness(row_curves, u, h) : Roughness();
  const Roughness column_roughness = use_columns ? FamilyRoughness(column_curves, v, h) : Roughness();
  const double noise_mm2 = std::max(1e-4, result.fit_rms_mm * result.fit_rms_mm);
  const Eigen::Index m = grid.num_vertices();
  Eigen::VectorXd depth = Eigen::VectorXd::Zero(m), gap = Eigen::VectorXd::Zero(m);
  std::vector<bool> known(static_cast<std::size_t>(m), false);
  for (int i = 0; i < grid.sternal; ++i) {
    for (int j = 0; j < grid.lateral; ++j) {
      const Eigen::Index k = grid.Index(i, j);
      double sum_w = 0.0, sum_wd = 0.0, best_gap = std::numeric_limits<double>::infinity();
      auto add = [&](const ProfileCurve& c, double t, const Roughness& roughness) {
        if (!c.valid()) return;
        const double g = c.DistanceToData(t);
        // (1 mm + g)^2 keeps the nearer data ahead where both families are equally regular.
        const double w = 1.0 / ((noise_mm2 + BridgingErrorSquared(c, t, roughness)) * (1.0 + g) * (1.0 + g));
        sum_w += w;
        sum_wd += w * c(t);
        best_gap = std::min(best_gap, g);
      };
      if (use_rows) add(row_curves[i], u[j], row_roughness);
      if (use_columns) add(column_curves[j], v[i], column_roughness);
      if (sum_w == 0.0) continue;
      depth[k] = sum_wd / sum_w;
      gap[k] = best_gap;
      known[k] = true;
    }
  }
  // 5. Vertices that no fitted section passes through (a corner beyond the data in both directions).
  ExtrapolateAlongGridLines(grid, u, v, options.fit,
                            std::min({options.min_profile_points, grid.lateral, grid.sternal}), &known,
                            &depth, &gap);
  Eigen::Index missing = 0, first_missing = -1;
  for (Eigen::Index k = 0; k < m; ++k) {
    if (!known[k] && missing++ == 0) first_missing = k;
  }
  if (missing > 0) {
    const auto i = static_cast<int>(first_missing / grid.lateral),
               j = static_cast<int>(first_missing % grid.lateral);
    ThrowBadInput(what, std::to_string(missing) + " of " + std::to_string(m) +
                            " grid vertices have no fitted section near them (first: row " +
                            std::to_string(i) + ", column " + std::to_string(j) +
                            "); the surface does not reach that part of the ROI");
  }
  const double spacing_u = roi.width() / (grid.lateral - 1), spacing_v = roi.height() / (grid.sternal - 1);
  const double spacing = std::max(spacing_u, spacing_v);
  const Eigen::Index supported = (gap.array() <= 2.0 * spacing).count();

  // 6. Vertices far from every profile's data: filled in 2D from the vertices around them, which sees a
  //    feature narrower than the hole (the sternal groove) from all sides (docs/model.md).
  result.vertices_inpainted = FillGridHoles(grid, spacing_u, spacing_v, gap, options.holes, &depth);

  // 7. Grid vertices back in the surface's frame.
  Points3 grid_uvw(m, 3);
  for (int i = 0; i < grid.sternal; ++i) {
    for (int j = 0; j < grid.lateral; ++j)
      grid_uvw.row(grid.Index(i, j)) << u[j], v[i], depth[grid.Index(i, j)];
  }
  result.mesh.vertices.positions = roi.FromRoi(grid_uvw);
  result.mesh.vertices.scalars["depth_mm"] = depth;
  result.mesh.vertices.scalars["data_gap_mm"] = gap;
  result.mesh.faces = GridFaces(grid);
  result.shape_vector = ToShapeVector(result.mesh.vertices.positions);
  result.max_data_gap_mm = gap.maxCoeff();
  result.supported_fraction = static_cast<double>(supported) / static_cast<double>(m);
  std::ostringstream msg;
  msg << grid.lateral << "x" << grid.sternal << " grid from " << result.profiles_fitted << " profiles ("
      << ToString(options.fit.kind) << "), fit RMS " << result.fit_rms_mm << " mm, largest data gap "
      << result.max_data_gap_mm << " mm, " << result.vertices_inpainted << " vertices filled in 2D";
  result.message = msg.str();
  return result;
}

CrossSectionResult ResampleSurface(const TriangleMesh& surface, const LandmarkSet& landmarks,
                                   const ChestRoiOptions& roi_options, const CrossSectionOptions& options,
                                   const std::string& what) {
  const ChestRoi roi = ComputeChestRoi(landmarks, roi_options, what + " landmarks");
  return ResampleCrossSections(surface, roi, options, what);
}

}  // namespace pectus
