// pectus: simple 2D charts (lines, bars, histograms) as images, for reports and docs.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "shape/render/image.h"

namespace pectus::render {

/// One curve of a line chart.
struct Series {
  std::string label;      ///< legend entry (empty: no entry)
  std::vector<double> x;  ///< abscissae
  std::vector<double> y;  ///< ordinates, one per x
  Rgb colour{31, 119, 180};
  bool markers = true;  ///< draw a dot at each point
  bool dashed = false;
};

/// Axes and frame of a chart.
struct PlotOptions {
  std::string title;
  std::string x_label;
  std::string y_label;
  int width = 800;
  int height = 500;
  std::optional<double> x_min, x_max, y_min, y_max;  ///< default: the data's range, padded
  bool log_y = false;
};

/// A line chart of one or more series, with axes, ticks, grid and legend.
Image PlotLines(const std::vector<Series>& series, const PlotOptions& options);
/// A bar chart: one bar per value, labelled underneath; `overlay` adds line series on top (e.g. a
/// cumulative curve over per-mode bars).
Image PlotBars(const std::vector<std::string>& labels, const std::vector<double>& values,
               const PlotOptions& options, const std::vector<Series>& overlay = {});
/// A histogram of `values` in `bins` equal bins over [lo, hi] (default: the data's range).
Image PlotHistogram(const std::vector<double>& values, int bins, const PlotOptions& options,
                    std::optional<double> lo = std::nullopt, std::optional<double> hi = std::nullopt);

}  // namespace pectus::render
