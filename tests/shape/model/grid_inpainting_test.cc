// 2D hole filling of a grid of heights: the fill reproduces exactly the polynomials its energy does not
// see (cubics for q = 2, quintics for q = 3 inside a hole; past the border, linear for q = 2 and quadratic
// for q = 3), and components of a mask are labelled with their border contact.
#include "shape/model/grid_inpainting.h"

#include <gtest/gtest.h>

#include <functional>

#include "shape/core/error.h"

namespace pectus {
namespace {

constexpr double kDu = 3.0, kDv = 2.0;  // mm, as the 51 x 101 grid over a 150 x 200 mm ROI

// Values of h(u, v) on a grid, and the mask of vertices outside the disk of `radius` around (cu, cv)
// (grid units).
struct Field {
  GridSize grid{31, 41};
  Eigen::VectorXd values;
  std::vector<bool> known;
  Field(const std::function<double(double, double)>& h, double cu, double cv, double radius) {
    values.resize(grid.num_vertices());
    known.resize(static_cast<std::size_t>(grid.num_vertices()));
    for (int i = 0; i < grid.sternal; ++i) {
      for (int j = 0; j < grid.lateral; ++j) {
        values[grid.Index(i, j)] = h(kDu * j, kDv * i);
        known[grid.Index(i, j)] = std::hypot(j - cu, i - cv) > radius;
      }
    }
  }
  // Max |fill - h| over the unknown vertices, after scrambling them.
  double FillError(const GridInpaintingOptions& options) const {
    Eigen::VectorXd scrambled = values;
    for (Eigen::Index k = 0; k < scrambled.size(); ++k) {
      if (!known[k]) scrambled[k] = 1e3 * std::sin(double(k));
    }
    const Eigen::VectorXd filled = InpaintGrid(grid, kDu, kDv, scrambled, known, options);
    return (filled - values).cwiseAbs().maxCoeff();
  }
};

TEST(GridInpainting, ThinPlateReproducesACubicInsideAHole) {
  const Field f(
      [](double u, double v) { return 1e-4 * u * u * u - 2e-4 * u * u * v + 3e-3 * v * v + 0.2 * u + 5.0; },
      15, 20, 6.0);
  EXPECT_LT(f.FillError({.order = 2, .stretch = 1.0}), 1e-8);
  EXPECT_LT(f.FillError({.order = 2, .stretch = 2.5}), 1e-8);  // any stretch: still a cubic
}

TEST(GridInpainting, ThirdOrderReproducesAQuinticInsideAHole) {
  const Field f(
      [](double u, double v) { return 1e-8 * std::pow(u, 5) - 1e-7 * u * u * v * v * v + 1e-3 * v * v; }, 15,
      20, 6.0);
  EXPECT_LT(f.FillError({.order = 3, .stretch = 1.0}), 1e-7);
  // Thin plate does not: a quintic is not biharmonic.
  EXPECT_GT(f.FillError({.order = 2, .stretch = 1.0}), 1e-4);
}

TEST(GridInpainting, NaturalBoundaryContinuesLinearlyOrWithConstantCurvature) {
  // A hole across the lower-left corner of the grid.
  const Field linear([](double u, double v) { return 0.3 * u - 0.1 * v + 2.0; }, 0, 0, 8.0);
  EXPECT_LT(linear.FillError({.order = 2, .stretch = 1.0}), 1e-8);
  const Field quadratic([](double u, double v) { return -u * u / 320.0 + 0.02 * u * v - v * v / 500.0; }, 0,
                        0, 8.0);
  EXPECT_LT(quadratic.FillError({.order = 3, .stretch = 1.0}), 1e-7);
  EXPECT_GT(quadratic.FillError({.order = 2, .stretch = 1.0}), 0.05);  // thin plate goes on linearly
}

TEST(GridInpainting, StretchAppliesAboutTheSternalLineOnlyWhenColumnPositionsAreGiven) {
  const GridInpaintingOptions o{.order = 2, .stretch = 3.0, .stretch_band_mm = 15.0};
  EXPECT_DOUBLE_EQ(o.StretchAt(0.0), 3.0);
  EXPECT_DOUBLE_EQ(o.StretchAt(-15.0), 3.0);
  EXPECT_DOUBLE_EQ(o.StretchAt(22.5), 2.0);
  EXPECT_DOUBLE_EQ(o.StretchAt(-40.0), 1.0);
  // A hole far from the sternal line (u from 60 mm on) is filled isotropically; without the column
  // positions the stretch applies everywhere.
  const Field f([](double u, double v) { return std::sin(u / 20.0) * std::cos(v / 25.0) * 10.0; }, 15, 20, 6);
  Eigen::VectorXd u(f.grid.lateral);
  for (int j = 0; j < f.grid.lateral; ++j) u[j] = 60.0 + kDu * j;
  const Eigen::VectorXd banded = InpaintGrid(f.grid, kDu, kDv, f.values, f.known, o, u);
  const Eigen::VectorXd isotropic = InpaintGrid(f.grid, kDu, kDv, f.values, f.known, {.stretch = 1.0});
  const Eigen::VectorXd stretched = InpaintGrid(f.grid, kDu, kDv, f.values, f.known, o);
  EXPECT_LT((banded - isotropic).cwiseAbs().maxCoeff(), 1e-9);
  EXPECT_GT((stretched - isotropic).cwiseAbs().maxCoeff(), 1e-3);
  EXPECT_THROW(InpaintGrid(f.grid, kDu, kDv, f.values, f.known, o, u.head(3)), Error);
}

TEST(GridInpainting, ComponentsAndTheirBorderContact) {
  const GridSize grid{6, 5};
  std::vector<bool> mask(30, false);
  for (int k : {7, 8, 13}) mask[k] = true;  // (1,1), (1,2), (2,1): inside
  for (int k : {24, 25}) mask[k] = true;    // (4,0), (4,1): on the border
  std::vector<bool> border;
  const Eigen::VectorXi label = LabelGridComponents(grid, mask, &border);
  ASSERT_EQ(border.size(), 2u);
  EXPECT_EQ(label[7], label[8]);
  EXPECT_EQ(label[7], label[13]);
  EXPECT_EQ(label[24], label[25]);
  EXPECT_NE(label[7], label[24]);
  EXPECT_EQ(label[0], -1);
  EXPECT_FALSE(border[label[7]]);
  EXPECT_TRUE(border[label[24]]);
}

TEST(GridInpainting, RejectsBadInput) {
  const GridSize grid{5, 5};
  const Eigen::VectorXd values = Eigen::VectorXd::Zero(25);
  EXPECT_THROW(InpaintGrid(grid, kDu, kDv, values, std::vector<bool>(25, false)), Error);
  EXPECT_THROW(InpaintGrid(grid, kDu, kDv, values, std::vector<bool>(24, true)), Error);
  EXPECT_THROW(InpaintGrid(grid, kDu, kDv, values, std::vector<bool>(25, true), {.order = 4}), Error);
  EXPECT_THROW(InpaintGrid(grid, 0.0, kDv, values, std::vector<bool>(25, true)), Error);
}

}  // namespace
}  // namespace pectus
