// merge_grid_benchmark: one PNG of success rate, pose error and shape error over the grid, per method
// (viridis, readable for colour-blind eyes; every cell carries its number).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "shape/render/colormap.h"
#include "shape/render/image.h"

namespace pectus::merge_grid {

/// One cell's figures for the picture (NaN: not run).
struct CellFigure {
  double skin_mm = 0.0, overlap = 0.0;
  std::string sampling;
  int sweeps = 0;
  std::string method;
  double success = NAN, rms_mm = NAN, shape_rms_mm = NAN;
  double surface_fit_shape_rms_mm = NAN;  ///< the issue-13 shape figure: after the rigid fit to the surface
};

namespace figure_detail {

inline std::string Format(const char* format, double value) {
  char text[32];
  std::snprintf(text, sizeof text, format, value);
  return text;
}

// A table: rows skin error, columns overlap; colour and text from value(cell).
template <class Value>
render::Image Panel(const std::vector<CellFigure>& cells, const std::vector<double>& skins,
                    const std::vector<double>& overlaps, const std::string& title, double lo, double hi,
                    const char* format, Value value) {
  const int cw = 64, ch = 34, left = 70, top = 62;
  int text_width = 0, text_height = 0;
  render::TextSize(title, 0.42, 1, &text_width, &text_height);
  const int width = std::max(left + cw * static_cast<int>(overlaps.size()) + 8, text_width + 12);
  render::Image image(width, top + ch * static_cast<int>(skins.size()) + 8, render::kWhite);
  render::DrawText(&image, 4, 18, title, 0.42);
  render::DrawText(&image, left, 38, "overlap", 0.36);
  render::DrawText(&image, 4, top - 6, "skin mm", 0.36);
  for (std::size_t c = 0; c < overlaps.size(); ++c)
    render::DrawText(&image, left + static_cast<int>(c) * cw + 14, top - 6, Format("%.2f", overlaps[c]),
                     0.38);
  for (std::size_t r = 0; r < skins.size(); ++r) {
    const int y0 = top + static_cast<int>(r) * ch;
    render::DrawText(&image, 20, y0 + 22, Format("%.0f", skins[r]), 0.42);
    for (std::size_t c = 0; c < overlaps.size(); ++c) {
      const int x0 = left + static_cast<int>(c) * cw;
      double v = NAN;
      for (const CellFigure& f : cells)
        if (f.skin_mm == skins[r] && f.overlap == overlaps[c]) v = value(f);
      const render::Rgb colour = std::isnan(v) ? render::Rgb{230, 230, 230}
                                               : render::MapColor(v, lo, hi, render::Colormap::kViridis);
      render::FillRect(&image, x0, y0, x0 + cw - 2, y0 + ch - 2, colour);
      if (std::isnan(v)) {
        render::DrawText(&image, x0 + 8, y0 + 22, "none", 0.42);  // every run threw
        continue;
      }
      const double luminance = 0.299 * colour.r + 0.587 * colour.g + 0.114 * colour.b;
      render::DrawText(&image, x0 + 8, y0 + 22, Format(format, v), 0.42,
                       luminance > 128 ? render::kBlack : render::kWhite);
    }
  }
  return image;
}

}  // namespace figure_detail

/// The picture: for each method (rows of blocks) and each sampling x sweep count (columns), three tables
/// over skin error (rows) x overlap (columns): success rate (0-1), the points' RMS distance from their true
/// positions after the rigid fit (pose error, 0-2 mm, clipped) and the shape's RMS error after the rigid fit
/// to the true surface (0-0.3 mm, clipped; the issue-13 line is 0.06). A sweep slid along a smooth surface
/// shows in the second and not in the third.
inline void WriteGridFigure(const std::vector<CellFigure>& cells, const std::filesystem::path& path,
                            const std::string& title) {
  auto sorted_unique = [](std::vector<double> v) {
    std::sort(v.begin(), v.end());
    v.erase(std::unique(v.begin(), v.end()), v.end());
    return v;
  };
  std::vector<double> skins, overlaps;
  std::vector<std::string> methods, samplings;
  std::vector<int> counts;
  for (const CellFigure& f : cells) {
    skins.push_back(f.skin_mm);
    overlaps.push_back(f.overlap);
    if (std::find(methods.begin(), methods.end(), f.method) == methods.end()) methods.push_back(f.method);
    if (std::find(samplings.begin(), samplings.end(), f.sampling) == samplings.end())
      samplings.push_back(f.sampling);
    if (std::find(counts.begin(), counts.end(), f.sweeps) == counts.end()) counts.push_back(f.sweeps);
  }
  skins = sorted_unique(skins);
  overlaps = sorted_unique(overlaps);
  std::sort(counts.begin(), counts.end());
  std::vector<render::Image> rows;
  for (const std::string& method : methods) {
    std::vector<render::Image> blocks;
    for (const std::string& sampling : samplings) {
      for (int n : counts) {
        std::vector<CellFigure> subset;
        for (const CellFigure& f : cells)
          if (f.method == method && f.sampling == sampling && f.sweeps == n) subset.push_back(f);
        if (subset.empty()) continue;
        const std::string name = method + ", " + sampling + ", " + std::to_string(n);
        blocks.push_back(render::VStack(
            {figure_detail::Panel(subset, skins, overlaps, name + ": success", 0.0, 1.0, "%.2f",
                                  [](const CellFigure& f) { return f.success; }),
             figure_detail::Panel(subset, skins, overlaps, name + ": pose RMS mm", 0.0, 2.0, "%.2f",
                                  [](const CellFigure& f) { return f.rms_mm; }),
             figure_detail::Panel(subset, skins, overlaps, name + ": shape RMS mm", 0.0, 0.3, "%.3f",
                                  [](const CellFigure& f) { return f.surface_fit_shape_rms_mm; })},
            6));
      }
    }
    rows.push_back(render::HStack(blocks, 16));
  }
  const render::Image bars =
      render::HStack({render::ColorBar(0.0, 1.0, render::Colormap::kViridis, "success rate", 240),
                      render::ColorBar(0.0, 2.0, render::Colormap::kViridis, "pose RMS mm (clipped)", 240),
                      render::ColorBar(0.0, 0.3, render::Colormap::kViridis, "shape RMS mm (clipped)", 240)},
                     8);
  render::Image all = render::HStack({render::VStack(rows, 16), bars}, 16);
  int text_width = 0, text_height = 0;
  render::TextSize(title, 0.7, 1, &text_width, &text_height);
  if (all.width < text_width + 20) all = render::HStack({all, render::Image(text_width + 20 - all.width, 1)});
  render::WritePng(render::WithTitle(all, title), path);
}

}  // namespace pectus::merge_grid
