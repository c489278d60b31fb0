#include "shape/model/grid_inpainting.h"

#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <algorithm>
#include <cmath>
#include <cstdlib>

#include "shape/core/enum_names.h"
#include "shape/core/error.h"

namespace pectus {
namespace {

// Coefficients of the forward difference of order n: (-1)^(n - p) binom(n, p), p = 0..n.
std::vector<double> Difference(int n) {
  std::vector<double> c(static_cast<std::size_t>(n) + 1);
  double binom = 1.0;
  for (int p = 0; p <= n; ++p) {
    c[p] = ((n - p) % 2 == 0 ? 1.0 : -1.0) * binom;
    binom = binom * (n - p) / (p + 1);
  }
  return c;
}

}  // namespace

double GridInpaintingOptions::StretchAt(double u_mm) const {
  if (!std::isfinite(stretch_band_mm)) return stretch;
  const double beyond = std::clamp(std::abs(u_mm) / stretch_band_mm - 1.0, 0.0, 1.0);
  return stretch + (1.0 - stretch) * beyond;
}

bool GridInpaintingOptions::IsValid(std::string* why) const {
  if (order != 2 && order != 3) {
    if (why != nullptr) *why = "grid inpainting order must be 2 or 3";
    return false;
  }
  if (!(stretch > 0.0) || !std::isfinite(stretch)) {
    if (why != nullptr) *why = "grid inpainting stretch must be > 0";
    return false;
  }
  if (!(stretch_band_mm > 0.0)) {
    if (why != nullptr) *why = "grid inpainting stretch band must be > 0 mm";
    return false;
  }
  return true;
}

Eigen::VectorXd InpaintGrid(const GridSize& grid, double spacing_u_mm, double spacing_v_mm,
                            const Eigen::VectorXd& values, const std::vector<bool>& known,
                            const GridInpaintingOptions& options, const Eigen::VectorXd& u_mm) {
  std::string why;
  if (!grid.IsValid(&why) || !options.IsValid(&why)) ThrowUsage(why);
  const Eigen::Index m = grid.num_vertices();
  if (values.size() != m || static_cast<Eigen::Index>(known.size()) != m)
    ThrowUsage("grid inpainting: values and mask must have one entry per grid vertex");
  if (!(spacing_u_mm > 0.0) || !(spacing_v_mm > 0.0))
    ThrowUsage("grid inpainting: grid spacings must be > 0 mm");
  if (u_mm.size() != 0 && u_mm.size() != grid.lateral)
    ThrowUsage("grid inpainting: one lateral position per grid column expected");

  // Unknown vertices are numbered 0..n-1.
  std::vector<int> unknown_index(static_cast<std::size_t>(m), -1);
  int n = 0;
  for (Eigen::Index k = 0; k < m; ++k) {
    if (!known[k]) unknown_index[k] = n++;
  }
  Eigen::VectorXd out = values;
  if (n == 0) return out;
  if (n == m) ThrowFailure("grid inpainting: no grid vertex has a value");

  // Normal equations of E restricted to the unknowns: Q_uu h_u = -Q_uk h_k.
  const int q = options.order;
  const double dv = spacing_v_mm;
  std::vector<Eigen::Triplet<double>> triplets;
  Eigen::VectorXd rhs = Eigen::VectorXd::Zero(n);
  std::vector<std::pair<Eigen::Index, double>> stencil;
  double binom = 1.0;  // binom(q, a)
  for (int a = 0; a <= q; binom = binom * (q - a) / (a + 1), ++a) {
    const int b = q - a;
    if (a >= grid.lateral || b >= grid.sternal) continue;
    const std::vector<double> ca = Difference(a), cb = Difference(b);
    for (int i = 0; i + b < grid.sternal; ++i) {
      for (int j = 0; j + a < grid.lateral; ++j) {
        // The stretch at the stencil's centre column.
        const double stretch =
            u_mm.size() == 0 ? options.stretch : options.StretchAt(0.5 * (u_mm[j] + u_mm[j + a]));
        const double scale = 1.0 / (std::pow(stretch * spacing_u_mm, a) * std::pow(dv, b));
        stencil.clear();
        bool touches_unknown = false;
        for (int y = 0; y <= b; ++y) {
          for (int x = 0; x <= a; ++x) {
            const Eigen::Index k = grid.Index(i + y, j + x);
            stencil.emplace_back(k, cb[y] * ca[x] * scale);
            touches_unknown = touches_unknown || unknown_index[k] >= 0;
          }
        }
        if (!touches_unknown) continue;
        for (const auto& [r, cr] : stencil) {
          const int ur = unknown_index[r];
          if (ur < 0) continue;
          for (const auto& [c, cc] : stencil) {
            const int uc = unknown_index[c];
            if (uc >= 0) {
              triplets.emplace_back(ur, uc, binom * cr * cc);
            } else {
              rhs[ur] -= binom * cr * cc * values[c];
            }
          }
        }
      }
    }
  }
  Eigen::SparseMatrix<double> Q(n, n);
  Q.setFromTriplets(triplets.begin(), triplets.end());
  const Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt(Q);
  const double largest = Q.diagonal().cwiseAbs().maxCoeff();
  if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().minCoeff() > 1e-12 * largest)) {
    ThrowFailure("grid inpainting: the known grid vertices do not determine the " + std::to_string(n) +
                 " unknown ones (a hole with too few known vertices around it)");
  }
  const Eigen::VectorXd h = ldlt.solve(rhs);
  for (Eigen::Index k = 0; k < m; ++k) {
    if (unknown_index[k] >= 0) out[k] = h[unknown_index[k]];
  }
  return out;
}

Eigen::VectorXi LabelGridComponents(const GridSize& grid, const std::vector<bool>& mask,
                                    std::vector<bool>* touches_border) {
  const Eigen::Index m = grid.num_vertices();
  Eigen::VectorXi label = Eigen::VectorXi::Constant(m, -1);
  touches_border->clear();
  std::vector<Eigen::Index> stack;
  int next = 0;
  for (Eigen::Index seed = 0; seed < m; ++seed) {
    if (!mask[seed] || label[seed] >= 0) continue;
    bool border = false;
    label[seed] = next;
    stack.assign(1, seed);
    while (!stack.empty()) {
      const Eigen::Index k = stack.back();
      stack.pop_back();
      const int i = static_cast<int>(k / grid.lateral), j = static_cast<int>(k % grid.lateral);
      border = border || i == 0 || j == 0 || i == grid.sternal - 1 || j == grid.lateral - 1;
      const int neighbours[4][2] = {{i - 1, j}, {i + 1, j}, {i, j - 1}, {i, j + 1}};
      for (const auto& [ni, nj] : neighbours) {
        if (ni < 0 || nj < 0 || ni >= grid.sternal || nj >= grid.lateral) continue;
        const Eigen::Index nk = grid.Index(ni, nj);
        if (mask[nk] && label[nk] < 0) label[nk] = next, stack.push_back(nk);
      }
    }
    touches_border->push_back(border);
    ++next;
  }
  return label;
}

void ExtrapolateAlongGridLines(const GridSize& grid, const Eigen::VectorXd& u, const Eigen::VectorXd& v,
                               const ProfileFitOptions& fit, int min_known, std::vector<bool>* known_in,
                               Eigen::VectorXd* depth_in, Eigen::VectorXd* gap_in) {
  std::vector<bool>& known = *known_in;
  Eigen::VectorXd& depth = *depth_in;
  Eigen::VectorXd& gap = *gap_in;
  for (bool progress = true; progress;) {
    progress = false;
    for (int pass = 0; pass < 2; ++pass) {
      const bool by_rows = pass == 0;
      const int lines = by_rows ? grid.sternal : grid.lateral, along = by_rows ? grid.lateral : grid.sternal;
      const Eigen::VectorXd& t_all = by_rows ? u : v;
      for (int line = 0; line < lines; ++line) {
        auto index = [&](int a) { return by_rows ? grid.Index(line, a) : grid.Index(a, line); };
        std::vector<double> t, y;
        std::vector<int> known_at;
        for (int a = 0; a < along; ++a) {
          if (known[index(a)]) t.push_back(t_all[a]), y.push_back(depth[index(a)]), known_at.push_back(a);
        }
        if (static_cast<int>(t.size()) == along || static_cast<int>(t.size()) < min_known) continue;
        const ProfileCurve c =
            FitProfile(Eigen::Map<const Eigen::VectorXd>(t.data(), static_cast<Eigen::Index>(t.size())),
                       Eigen::Map<const Eigen::VectorXd>(y.data(), static_cast<Eigen::Index>(y.size())),
                       t_all[0], t_all[along - 1], fit);
        if (!c.valid()) continue;
        for (int a = 0; a < along; ++a) {
          const Eigen::Index k = index(a);
          if (known[k]) continue;
          depth[k] = c(t_all[a]);
          // The gap grows by the distance to the nearest vertex that had a value.
          int nearest = known_at.front();
          for (int b : known_at) {
            if (std::abs(b - a) < std::abs(nearest - a)) nearest = b;
          }
          gap[k] = gap[index(nearest)] + std::abs(t_all[a] - t_all[nearest]);
          known[k] = true;
          progress = true;
        }
      }
    }
  }
}

constexpr EnumNames<GridHoleFill, 3> kGridHoleFillNames{{{GridHoleFill::kProfiles, "profiles"},
                                                         {GridHoleFill::kInpaint, "inpaint"},
                                                         {GridHoleFill::kInpaintInside, "inpaint-inside"}}};

GridHoleFill ParseGridHoleFill(const std::string& text) {
  return ParseEnum(kGridHoleFillNames, text, [&] {
    return "hole fill '" + text + "' is not " + ListEnumNames(kGridHoleFillNames, "'", ", ", " or ");
  });
}

std::string ToString(GridHoleFill fill) { return EnumToString(kGridHoleFillNames, fill, "inpaint"); }

bool GridHoleFillOptions::IsValid(std::string* why) const {
  if (!(gap_mm >= 0.0) || !std::isfinite(gap_mm)) {
    if (why != nullptr) *why = "hole-fill gap must be >= 0 mm";
    return false;
  }
  return inpainting.IsValid(why);
}

Eigen::Index FillGridHoles(const GridSize& grid, double spacing_u_mm, double spacing_v_mm,
                           const Eigen::VectorXd& gap, const GridHoleFillOptions& options,
                           Eigen::VectorXd* depth, std::vector<bool>* filled_mask,
                           const Eigen::VectorXd& u_mm) {
  const Eigen::Index m = grid.num_vertices();
  if (filled_mask != nullptr) filled_mask->assign(static_cast<std::size_t>(m), false);
  if (options.mode == GridHoleFill::kProfiles) return 0;
  std::vector<bool> hole(static_cast<std::size_t>(m));
  for (Eigen::Index k = 0; k < m; ++k) hole[k] = !(gap[k] <= options.gap_mm);
  if (options.mode == GridHoleFill::kInpaintInside) {
    std::vector<bool> touches_border;
    const Eigen::VectorXi label = LabelGridComponents(grid, hole, &touches_border);
    for (Eigen::Index k = 0; k < m; ++k) {
      if (label[k] >= 0 && touches_border[label[k]]) hole[k] = false;
    }
  }
  std::vector<bool> known(static_cast<std::size_t>(m));
  Eigen::Index filled = 0;
  for (Eigen::Index k = 0; k < m; ++k) known[k] = !hole[k], filled += hole[k] ? 1 : 0;
  const int q = options.inpainting.order;
  if (filled == 0 || m - filled < 4 * q * q) return 0;
  *depth = InpaintGrid(grid, spacing_u_mm, spacing_v_mm, *depth, known, options.inpainting, u_mm);
  if (filled_mask != nullptr) *filled_mask = hole;
  return filled;
}

}  // namespace pectus
