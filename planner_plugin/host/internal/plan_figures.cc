#include "planner_plugin/host/internal/plan_figures.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "planner_plugin/host/chest_registration.h"
#include "shape/render/colormap.h"

namespace pectus::planner {

render::View AverageChestFrontView(const AverageChest& average, int width, int height) {
  const Eigen::Vector3d anterior = AnteriorDirection(average.mesh, "average chest");
  const Eigen::Vector3d down = (average.landmarks.Position("xiphoid", average.landmark_source) -
                                average.landmarks.Position("sternal_notch", average.landmark_source))
                                   .normalized();
  render::View view;
  view.direction = -anterior;
  view.up = (-down - (-down).dot(anterior) * anterior).normalized();
  view.width = width;
  view.height = height;
  view.frame = ComputeBounds(average.mesh.vertices.positions);
  return view;
}

render::View PatientObliqueView(const Bounds3& bounds, int width, int height) {
  render::View view;
  view.direction = Eigen::Vector3d(0.35, 1.0, -0.45).normalized();  // LPS: from the front (-y), right, above
  view.up = Eigen::Vector3d(0, 0, 1);
  view.width = width;
  view.height = height;
  view.frame = bounds;
  return view;
}

Colors3 DifferenceColors(const Eigen::VectorXd& values_mm, double limit_mm) {
  return render::MapColors(values_mm, -limit_mm, limit_mm, render::Colormap::kDiverging);
}

render::Image RenderDifference(const TriangleMesh& mesh, const Eigen::VectorXd& values_mm, double limit_mm,
                               const render::View& view, const std::string& title) {
  const Colors3 colors = DifferenceColors(values_mm, limit_mm);
  return render::WithTitle(render::RenderMesh(mesh, view, &colors), title);
}

render::Image SideBySide(const std::vector<render::Image>& pictures, double limit_mm,
                         const std::string& label) {
  std::vector<render::Image> row = pictures;
  const int height = pictures.empty() ? 600 : pictures.front().height;
  row.push_back(render::ColorBar(-limit_mm, limit_mm, render::Colormap::kDiverging, label, height));
  return render::HStack(row, 8);
}

render::Image RenderRibcageDisplacement(const TriangleMesh& deformed_bone,
                                        const Eigen::VectorXd& displacement_mm, double limit_mm,
                                        const render::View& view, const std::string& title) {
  const Colors3 colors = render::MapColors(displacement_mm, 0.0, limit_mm, render::Colormap::kViridis);
  const render::Image picture = render::WithTitle(render::RenderMesh(deformed_bone, view, &colors), title);
  return render::HStack({picture, render::ColorBar(0.0, limit_mm, render::Colormap::kViridis,
                                                   "displacement, mm", picture.height)},
                        8);
}

render::Image RenderSearchMap(const PlacementSearchResult& search, const std::string& title) {
  const Eigen::MatrixXd& v = search.objective_mm;
  const int rows = static_cast<int>(v.rows()), cols = static_cast<int>(v.cols());
  const int cell_w = std::max(12, 560 / std::max(1, cols)), cell_h = std::max(16, 400 / std::max(1, rows));
  const int left = 90, top = 20, bottom = 60;
  render::Image image(left + cols * cell_w + 20, top + rows * cell_h + bottom);
  const double lo = v.minCoeff(), hi = std::max(v.maxCoeff(), lo + 1e-9);
  for (int i = 0; i < rows; ++i) {
    for (int j = 0; j < cols; ++j) {
      const int x0 = left + j * cell_w, y0 = top + i * cell_h;
      render::FillRect(&image, x0, y0, x0 + cell_w - 1, y0 + cell_h - 1,
                       render::MapColor(v(i, j), lo, hi, render::Colormap::kViridis));
    }
    char label[32];
    std::snprintf(label, sizeof(label), "%.3f L", search.positions[static_cast<std::size_t>(i)]);
    render::DrawText(&image, 4, top + i * cell_h + cell_h / 2 + 5, label, 0.45);
  }
  const int step = std::max(1, cols / 6);
  for (int j = 0; j < cols; j += step) {
    char label[32];
    std::snprintf(label, sizeof(label), "%.0f", search.forces_n[static_cast<std::size_t>(j)]);
    render::DrawText(&image, left + j * cell_w, top + rows * cell_h + 18, label, 0.45);
  }
  render::DrawText(&image, left, top + rows * cell_h + 44, "bar force, N (rows: bar position from the notch)",
                   0.5);
  // The refined best placement, at its place between the grid's cells.
  const double pi = (search.best.position - search.positions.front()) /
                    (search.positions.back() - search.positions.front()) * (rows - 1);
  const double fj = (search.best.force_n - search.forces_n.front()) /
                    (search.forces_n.back() - search.forces_n.front()) * (cols - 1);
  const int cx = left + static_cast<int>(std::lround((fj + 0.5) * cell_w));
  const int cy = top + static_cast<int>(std::lround((pi + 0.5) * cell_h));
  render::DrawLine(&image, cx - 8, cy, cx + 8, cy, render::kWhite, 3);
  render::DrawLine(&image, cx, cy - 8, cx, cy + 8, render::kWhite, 3);
  render::DrawLine(&image, cx - 8, cy, cx + 8, cy, render::kBlack, 1);
  render::DrawLine(&image, cx, cy - 8, cx, cy + 8, render::kBlack, 1);
  const render::Image titled = render::WithTitle(image, title);
  return render::HStack(
      {titled, render::ColorBar(lo, hi, render::Colormap::kViridis, "RMS difference, mm", titled.height)}, 8);
}

}  // namespace pectus::planner
