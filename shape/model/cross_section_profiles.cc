#include "shape/model/cross_section_profiles.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "shape/model/cross_section_resampler.h"

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

// Expected squared error (mm^2) of curve `c` at t beyond its fit residual (see ProfileRoughness).
double BridgingErrorSquared(const ProfileCurve& c, double t, const ProfileRoughness& r) {
  double below = 0.0, above = 0.0;
  c.DistancesToDataOnEachSide(t, &below, &above);
  if (std::isfinite(below) && std::isfinite(above)) return r.d4 * std::pow(below * above, 4) / 576.0;
  const double g = std::min(below, above);
  return r.d3 * std::pow(g, 6) / 36.0;
}

}  // namespace

SectionCurves FitSectionCurves(const TriangleMesh& surface, const ChestRoi& roi, const Eigen::VectorXd& u,
                               const Eigen::VectorXd& v, const CrossSectionOptions& options) {
  const bool use_rows = options.directions != SectionDirections::kColumns;
  const bool use_columns = options.directions != SectionDirections::kRows;
  const double margin = options.fit_margin_mm;

  // Every point in ROI coordinates (u, v, w).
  const Points3 uvw = roi.ToRoi(surface.vertices.positions);

  // Section profiles: rows cut at v = v_i give depth(u); columns cut at u = u_j give depth(v).
  std::vector<Profile> rows(use_rows ? v.size() : 0), columns(use_columns ? u.size() : 0);
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

  // A curve through each profile's front envelope.
  SectionCurves curves;
  curves.rows.resize(rows.size());
  curves.columns.resize(columns.size());
  auto fit_all = [&](std::vector<Profile>& profiles, std::vector<ProfileCurve>& fitted, double lo,
                     double hi) {
#pragma omp parallel for schedule(dynamic)
    for (std::size_t k = 0; k < profiles.size(); ++k) {
      KeepFrontEnvelope(options.envelope_bin_mm, options.envelope_depth_mm, &profiles[k]);
      if (static_cast<int>(profiles[k].t.size()) < options.min_profile_points) continue;
      const Eigen::Map<const Eigen::VectorXd> t(profiles[k].t.data(),
                                                static_cast<Eigen::Index>(profiles[k].t.size()));
      const Eigen::Map<const Eigen::VectorXd> y(profiles[k].y.data(),
                                                static_cast<Eigen::Index>(profiles[k].y.size()));
      fitted[k] = FitProfile(t, y, lo, hi, options.fit);
    }
  };
  fit_all(rows, curves.rows, u[0], u[u.size() - 1]);
  fit_all(columns, curves.columns, v[0], v[v.size() - 1]);
  return curves;
}

ProfileRoughness FamilyRoughness(const std::vector<ProfileCurve>& curves, const Eigen::VectorXd& t,
                                 double h) {
  ProfileRoughness r;
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

BlendedGrid BlendSectionCurves(const SectionCurves& curves, const GridSize& grid, const Eigen::VectorXd& u,
                               const Eigen::VectorXd& v, const ProfileRoughness& row_roughness,
                               const ProfileRoughness& column_roughness, double noise_mm2) {
  const Eigen::Index m = grid.num_vertices();
  BlendedGrid out;
  out.depth = Eigen::VectorXd::Zero(m);
  out.gap = Eigen::VectorXd::Zero(m);
  out.known.assign(static_cast<std::size_t>(m), false);
  for (int i = 0; i < grid.sternal; ++i) {
    for (int j = 0; j < grid.lateral; ++j) {
      const Eigen::Index k = grid.Index(i, j);
      double sum_w = 0.0, sum_wd = 0.0, best_gap = std::numeric_limits<double>::infinity();
      auto add = [&](const ProfileCurve& c, double t, const ProfileRoughness& roughness) {
        if (!c.valid()) return;
        const double g = c.DistanceToData(t);
        // (1 mm + g)^2 keeps the nearer data ahead where both families are equally regular.
        const double w = 1.0 / ((noise_mm2 + BridgingErrorSquared(c, t, roughness)) * (1.0 + g) * (1.0 + g));
        sum_w += w;
        sum_wd += w * c(t);
        best_gap = std::min(best_gap, g);
      };
      if (!curves.rows.empty()) add(curves.rows[i], u[j], row_roughness);
      if (!curves.columns.empty()) add(curves.columns[j], v[i], column_roughness);
      if (sum_w == 0.0) continue;
      out.depth[k] = sum_wd / sum_w;
      out.gap[k] = best_gap;
      out.known[k] = true;
    }
  }
  return out;
}

}  // namespace pectus
