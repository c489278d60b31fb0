#include "planner_plugin/ribcage/bar_contact.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "planner_plugin/ribcage/build_generic_ribcage.h"
#include "shape/core/error.h"

namespace pectus::planner {

BarShape BarShape::Flat(double level_z_mm, double y, double half_length_mm) {
  BarShape bar;
  bar.level_z_mm = level_z_mm;
  bar.x_mm = {-half_length_mm, half_length_mm};
  bar.y_mm = {y, y};
  return bar;
}

double BarShape::Y(double x) const {
  if (x <= x_mm.front()) return y_mm.front();
  if (x >= x_mm.back()) return y_mm.back();
  const auto hi = static_cast<std::size_t>(std::upper_bound(x_mm.begin(), x_mm.end(), x) - x_mm.begin());
  const double t = (x - x_mm[hi - 1]) / (x_mm[hi] - x_mm[hi - 1]);
  return y_mm[hi - 1] + t * (y_mm[hi] - y_mm[hi - 1]);
}

bool BarShape::IsValid(std::string* why) const {
  auto fail = [&](const std::string& m) {
    if (why) *why = "bar shape: " + m;
    return false;
  };
  if (x_mm.size() < 2 || x_mm.size() != y_mm.size())
    return fail("needs as many y as x stations, at least two");
  for (std::size_t i = 0; i < x_mm.size(); ++i) {
    if (!std::isfinite(x_mm[i]) || !std::isfinite(y_mm[i])) return fail("a station is not finite");
    if (i > 0 && !(x_mm[i] > x_mm[i - 1])) return fail("the x stations must ascend");
  }
  if (!std::isfinite(level_z_mm) || !std::isfinite(lift_mm))
    return fail("the level and the lift must be finite");
  return true;
}

bool BarContactOptions::IsValid(std::string* why) const {
  if (!(width_mm > 0.0) || !(tolerance_mm > 0.0) || max_sweeps < 1 || block_columns < 1) {
    if (why) *why = "bar contact: the width and tolerance must be > 0 mm, the sweeps and blocks >= 1";
    return false;
  }
  return true;
}

BarContactResult SolveBarContact(const RibcageFem& fem, const BarShape& bar,
                                 const BarContactOptions& options) {
  std::string why;
  if (!options.IsValid(&why) || !bar.IsValid(&why)) ThrowUsage(why);
  const PatientRibcage& ribcage = fem.ribcage();
  const TetMesh& mesh = ribcage.mesh;
  const Points3& x = mesh.nodes;
  const Eigen::Vector3d d = fem.options().push_direction.normalized();
  const auto n = static_cast<std::size_t>(mesh.num_nodes());

  // 1. Candidates: nodes of posterior-facing boundary faces of the sternum and the cartilages near the
  // bar level (the faces' corner triangle gives the outward normal; posterior is along -d).
  const MeshBoundary boundary = ExtractBoundary(mesh);
  std::vector<int> region_of(n, -1);
  for (Eigen::Index f = 0; f < boundary.faces.rows(); ++f) {
    const int region = mesh.regions(boundary.face_tet(f));
    if (region != kSternumRegion && region != kCartilageRegion) continue;
    const Eigen::Vector3d a = x.row(boundary.faces(f, 0)), b = x.row(boundary.faces(f, 1)),
                          c = x.row(boundary.faces(f, 2));
    if ((b - a).cross(c - a).dot(d) >= 0.0) continue;  // faces the front
    for (int k = 0; k < 6; ++k) {
      const std::int32_t node = boundary.faces(f, k);
      if (std::abs(x(node, 2) - bar.level_z_mm) > 0.5 * options.width_mm || !bar.Spans(x(node, 0))) continue;
      // A node on both a sternal and a cartilage face counts as sternum (the bar meets the bone there).
      int& r = region_of[static_cast<std::size_t>(node)];
      r = r == kSternumRegion ? r : region;
    }
  }
  BarContactResult out;
  for (std::size_t i = 0; i < n; ++i) {
    if (region_of[i] >= 0)
      out.nodes.push_back(static_cast<std::int32_t>(i)), out.regions.push_back(region_of[i]);
  }
  const auto m = static_cast<Eigen::Index>(out.nodes.size());
  if (m == 0) {
    ThrowFailure("bar contact: no node of the sternum's or the cartilages' back lies within " +
                 std::to_string(0.5 * options.width_mm) + " mm of the bar level z = " +
                 std::to_string(bar.level_z_mm) + " mm and within the bar's span");
  }
  // Gaps along the push direction d = -y: the node's coordinate -y_i against the bar's -Y(x_i) + lift.
  out.gap0_mm.resize(m);
  for (Eigen::Index i = 0; i < m; ++i) {
    const Eigen::Vector3d p = x.row(out.nodes[static_cast<std::size_t>(i)]);
    out.gap0_mm[i] = p.dot(d) - (-bar.Y(p.x()) + bar.lift_mm);
  }

  // 2. The condensed compliance C (m x m): the push-direction response of every candidate to a unit push
  // at each, blocks of right-hand sides on the one factorisation. Skipped when no gap is closed.
  out.force_n = Eigen::VectorXd::Zero(m);
  out.gap_mm = out.gap0_mm;
  if (out.gap0_mm.minCoeff() < 0.0) {
    Eigen::MatrixXd C(m, m);
    for (Eigen::Index first = 0; first < m; first += options.block_columns) {
      const Eigen::Index count = std::min<Eigen::Index>(options.block_columns, m - first);
      std::vector<LoadCase> cases(static_cast<std::size_t>(count));
      for (Eigen::Index k = 0; k < count; ++k) {
        cases[static_cast<std::size_t>(k)].name = "unit push at node " + std::to_string(out.nodes[first + k]);
        cases[static_cast<std::size_t>(k)].nodal_forces = Eigen::VectorXd::Zero(3 * mesh.num_nodes());
        cases[static_cast<std::size_t>(k)].nodal_forces.segment<3>(
            3 * out.nodes[static_cast<std::size_t>(first + k)]) = d;
      }
      const std::vector<Points3> u = fem.solver().Solve(cases);
      for (Eigen::Index k = 0; k < count; ++k) {
        for (Eigen::Index i = 0; i < m; ++i)
          C(i, first + k) =
              u[static_cast<std::size_t>(k)].row(out.nodes[static_cast<std::size_t>(i)]).dot(d.transpose());
      }
    }
    C = 0.5 * (C + C.transpose());  // symmetric up to the solver's rounding

    // 3. Projected Gauss-Seidel: f_i <- max(0, f_i - w_i / C_ii), keeping w = g0 + C f up to date.
    Eigen::VectorXd& f = out.force_n;
    Eigen::VectorXd w = out.gap0_mm;
    for (out.sweeps = 1; out.sweeps <= options.max_sweeps; ++out.sweeps) {
      for (Eigen::Index i = 0; i < m; ++i) {
        const double next = std::max(0.0, f[i] - w[i] / C(i, i));
        const double delta = next - f[i];
        if (delta != 0.0) {
          f[i] = next;
          w.noalias() += delta * C.col(i);
        }
      }
      out.residual_mm = 0.0;
      for (Eigen::Index i = 0; i < m; ++i)
        out.residual_mm = std::max(out.residual_mm, std::abs(std::min(f[i] * C(i, i), w[i])));
      if (out.residual_mm <= options.tolerance_mm) {
        out.converged = true;
        break;
      }
    }
    out.sweeps = std::min(out.sweeps, options.max_sweeps);
    out.gap_mm = w;
  } else {
    out.converged = true;
  }

  // 4. The deformed ribcage: the direct FE solve with the contact forces applied.
  LoadCase load{"bar contact forces", Eigen::VectorXd::Zero(3 * mesh.num_nodes()), {}};
  int sternum = 0, cartilage = 0;
  for (Eigen::Index i = 0; i < m; ++i) {
    if (out.force_n[i] <= 0.0) continue;
    load.nodal_forces.segment<3>(3 * out.nodes[static_cast<std::size_t>(i)]) += out.force_n[i] * d;
    out.total_force_n += out.force_n[i];
    ++out.contacts;
    ++(out.regions[static_cast<std::size_t>(i)] == kSternumRegion ? sternum : cartilage);
  }
  out.displacement =
      out.contacts > 0 ? fem.solver().Solve({load}).front() : Points3::Zero(mesh.num_nodes(), 3);
  char line[300];
  std::snprintf(
      line, sizeof(line),
      "bar at z = %.1f mm: %d of %lld candidates in contact (%d sternum, %d cartilage), total force %.1f N; "
      "%s after %d sweeps (residual %.2g mm)",
      bar.level_z_mm, out.contacts, static_cast<long long>(m), sternum, cartilage, out.total_force_n,
      out.converged ? "converged" : "NOT converged", out.sweeps, out.residual_mm);
  out.message = line;
  return out;
}

}  // namespace pectus::planner
