// pectus: line, bar and histogram charts drawn with OpenCV primitives (through image.h).
#include "shape/render/plot.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

namespace pectus::render {
namespace {

// A "nice" tick step (1, 2 or 5 times a power of ten) giving about `target` ticks over `range`.
double NiceStep(double range, int target) {
  if (!(range > 0)) return 1;
  const double raw = range / std::max(1, target);
  const double mag = std::pow(10.0, std::floor(std::log10(raw)));
  const double f = raw / mag;
  return (f < 1.5 ? 1 : f < 3 ? 2 : f < 7 ? 5 : 10) * mag;
}

std::string Format(double v, double step) {
  char buf[32];
  if (std::abs(v) >= 1e5 || (std::abs(v) < 1e-3 && v != 0)) {
    std::snprintf(buf, sizeof buf, "%.1e", v);
  } else {
    const int decimals = step >= 1 ? 0 : static_cast<int>(std::ceil(-std::log10(step) - 1e-9));
    std::snprintf(buf, sizeof buf, "%.*f", std::min(decimals, 4), std::abs(v) < step * 1e-6 ? 0.0 : v);
  }
  return buf;
}

// The axes of a chart: data ranges and the pixel rectangle they map to.
struct Axes {
  double x0, x1, y0, y1;  // data range (y in log10 when log_y)
  int left = 80, right, top = 40, bottom;
  bool log_y = false;
  int X(double x) const {
    return left + static_cast<int>(std::lround((x - x0) / (x1 - x0) * (right - left)));
  }
  int Y(double y) const {
    if (log_y) y = std::log10(std::max(y, 1e-300));
    return bottom - static_cast<int>(std::lround((y - y0) / (y1 - y0) * (bottom - top)));
  }
};

void Range(const std::vector<double>& v, double* lo, double* hi, bool positive_only) {
  for (double x : v) {
    if (!std::isfinite(x) || (positive_only && x <= 0)) continue;
    *lo = std::min(*lo, x);
    *hi = std::max(*hi, x);
  }
}

Axes MakeAxes(const PlotOptions& o, double xlo, double xhi, double ylo, double yhi) {
  Axes a;
  a.right = o.width - 20;
  a.bottom = o.height - 60;
  a.log_y = o.log_y;
  if (!(xhi > xlo)) {
    xlo -= 0.5;
    xhi += 0.5;
  }
  if (o.log_y) {
    ylo = std::log10(std::max(ylo, 1e-300));
    yhi = std::log10(std::max(yhi, 1e-300));
  }
  if (!(yhi > ylo)) {
    ylo -= 0.5;
    yhi += 0.5;
  }
  const double pad_y = o.log_y ? 0.05 * (yhi - ylo) : 0.05 * (yhi - ylo);
  a.x0 = o.x_min.value_or(xlo);
  a.x1 = o.x_max.value_or(xhi);
  a.y0 = o.y_min ? (o.log_y ? std::log10(*o.y_min) : *o.y_min) : ylo - pad_y;
  a.y1 = o.y_max ? (o.log_y ? std::log10(*o.y_max) : *o.y_max) : yhi + pad_y;
  if (!(a.x1 > a.x0)) a.x1 = a.x0 + 1;
  if (!(a.y1 > a.y0)) a.y1 = a.y0 + 1;
  return a;
}

void DrawFrame(Image* im, const Axes& a, const PlotOptions& o, bool x_ticks) {
  const Rgb grid{225, 225, 225};
  // y ticks and grid
  if (a.log_y) {
    for (int e = static_cast<int>(std::floor(a.y0)); e <= static_cast<int>(std::ceil(a.y1)); ++e) {
      if (e < a.y0 - 1e-9 || e > a.y1 + 1e-9) continue;
      const int y = a.Y(std::pow(10.0, e));
      DrawLine(im, a.left, y, a.right, y, grid);
      char buf[16];
      std::snprintf(buf, sizeof buf, "1e%d", e);
      DrawText(im, 8, y + 5, buf, 0.45);
    }
  } else {
    const double step = NiceStep(a.y1 - a.y0, 6);
    for (double v = std::ceil(a.y0 / step) * step; v <= a.y1 + 1e-9 * step; v += step) {
      const int y = a.Y(v);
      DrawLine(im, a.left, y, a.right, y, grid);
      const std::string t = Format(v, step);
      int tw, th;
      TextSize(t, 0.45, 1, &tw, &th);
      DrawText(im, a.left - tw - 6, y + 5, t, 0.45);
    }
  }
  if (x_ticks) {
    const double step = NiceStep(a.x1 - a.x0, 8);
    for (double v = std::ceil(a.x0 / step) * step; v <= a.x1 + 1e-9 * step; v += step) {
      const int x = a.X(v);
      DrawLine(im, x, a.top, x, a.bottom, grid);
      const std::string t = Format(v, step);
      int tw, th;
      TextSize(t, 0.45, 1, &tw, &th);
      DrawText(im, x - tw / 2, a.bottom + 18, t, 0.45);
    }
  }
  DrawLine(im, a.left, a.bottom, a.right, a.bottom, kBlack);
  DrawLine(im, a.left, a.top, a.left, a.bottom, kBlack);
  int tw, th;
  TextSize(o.title, 0.65, 1, &tw, &th);
  DrawText(im, (o.width - tw) / 2, 26, o.title, 0.65);
  TextSize(o.x_label, 0.5, 1, &tw, &th);
  DrawText(im, (a.left + a.right - tw) / 2, o.height - 14, o.x_label, 0.5);
  DrawText(im, 8, a.top - 10, o.y_label, 0.5);
}

void DrawSeries(Image* im, const Axes& a, const Series& s) {
  const std::size_t n = std::min(s.x.size(), s.y.size());
  for (std::size_t i = 0; i + 1 < n; ++i) {
    if (!std::isfinite(s.y[i]) || !std::isfinite(s.y[i + 1])) continue;
    if (a.log_y && (s.y[i] <= 0 || s.y[i + 1] <= 0)) continue;
    const int xa = a.X(s.x[i]), ya = a.Y(s.y[i]), xb = a.X(s.x[i + 1]), yb = a.Y(s.y[i + 1]);
    if (s.dashed) {
      const int segs = std::max(1, static_cast<int>(std::hypot(xb - xa, yb - ya) / 6));
      for (int k = 0; k < segs; k += 2) {
        DrawLine(im, xa + (xb - xa) * k / segs, ya + (yb - ya) * k / segs, xa + (xb - xa) * (k + 1) / segs,
                 ya + (yb - ya) * (k + 1) / segs, s.colour, 2);
      }
    } else {
      DrawLine(im, xa, ya, xb, yb, s.colour, 2);
    }
  }
  if (s.markers) {
    for (std::size_t i = 0; i < n; ++i) {
      if (!std::isfinite(s.y[i]) || (a.log_y && s.y[i] <= 0)) continue;
      FillRect(im, a.X(s.x[i]) - 2, a.Y(s.y[i]) - 2, a.X(s.x[i]) + 2, a.Y(s.y[i]) + 2, s.colour);
    }
  }
}

void DrawLegend(Image* im, const Axes& a, const std::vector<Series>& series) {
  int y = a.top + 16;
  for (const Series& s : series) {
    if (s.label.empty()) continue;
    int tw, th;
    TextSize(s.label, 0.45, 1, &tw, &th);
    const int x = a.right - tw - 40;
    FillRect(im, x - 4, y - 12, a.right - 4, y + 5, kWhite);
    DrawLine(im, x, y - 4, x + 24, y - 4, s.colour, 2);
    DrawText(im, x + 30, y, s.label, 0.45);
    y += 20;
  }
}

}  // namespace

Image PlotLines(const std::vector<Series>& series, const PlotOptions& options) {
  double xlo = std::numeric_limits<double>::infinity(), xhi = -xlo, ylo = xlo, yhi = -xlo;
  for (const Series& s : series) {
    Range(s.x, &xlo, &xhi, false);
    Range(s.y, &ylo, &yhi, options.log_y);
  }
  if (!std::isfinite(xlo)) xlo = 0, xhi = 1;
  if (!std::isfinite(ylo)) ylo = options.log_y ? 1 : 0, yhi = options.log_y ? 10 : 1;
  Image im(options.width, options.height);
  const Axes a = MakeAxes(options, xlo, xhi, ylo, yhi);
  DrawFrame(&im, a, options, true);
  for (const Series& s : series) DrawSeries(&im, a, s);
  DrawLegend(&im, a, series);
  return im;
}

Image PlotBars(const std::vector<std::string>& labels, const std::vector<double>& values,
               const PlotOptions& options, const std::vector<Series>& overlay) {
  const double n = static_cast<double>(values.size());
  double ylo = 0, yhi = 0;
  Range(values, &ylo, &yhi, options.log_y);
  for (const Series& s : overlay) Range(s.y, &ylo, &yhi, options.log_y);
  if (options.log_y && ylo <= 0) ylo = yhi > 0 ? yhi * 1e-3 : 1e-3;
  PlotOptions o = options;
  if (!o.x_min) o.x_min = 0.5;
  if (!o.x_max) o.x_max = n + 0.5;
  Image im(o.width, o.height);
  const Axes a = MakeAxes(o, 0.5, n + 0.5, ylo, yhi);
  DrawFrame(&im, a, o, false);
  const int bar_half = std::max(1, static_cast<int>((a.right - a.left) / std::max(1.0, n) * 0.35));
  const int label_every = std::max(1, static_cast<int>(n / 20));
  for (std::size_t i = 0; i < values.size(); ++i) {
    const int x = a.X(static_cast<double>(i + 1));
    const double base = a.log_y ? std::pow(10.0, a.y0) : std::max(0.0, a.y0);
    if (std::isfinite(values[i]) && (!a.log_y || values[i] > 0)) {
      FillRect(&im, x - bar_half, a.Y(values[i]), x + bar_half, a.Y(base), Rgb{31, 119, 180});
    }
    if (i < labels.size() && i % static_cast<std::size_t>(label_every) == 0) {
      int tw, th;
      TextSize(labels[i], 0.4, 1, &tw, &th);
      DrawText(&im, x - tw / 2, a.bottom + 18, labels[i], 0.4);
    }
  }
  for (const Series& s : overlay) DrawSeries(&im, a, s);
  DrawLegend(&im, a, overlay);
  return im;
}

Image PlotHistogram(const std::vector<double>& values, int bins, const PlotOptions& options,
                    std::optional<double> lo, std::optional<double> hi) {
  bins = std::max(1, bins);
  double dlo = std::numeric_limits<double>::infinity(), dhi = -dlo;
  Range(values, &dlo, &dhi, false);
  const double l = lo.value_or(std::isfinite(dlo) ? dlo : 0.0);
  double h = hi.value_or(std::isfinite(dhi) ? dhi : 1.0);
  if (!(h > l)) h = l + 1;
  std::vector<double> counts(static_cast<std::size_t>(bins), 0.0);
  for (double v : values) {
    if (!std::isfinite(v)) continue;
    const int b = std::clamp(static_cast<int>((v - l) / (h - l) * bins), 0, bins - 1);
    counts[static_cast<std::size_t>(b)] += 1;
  }
  double cmax = 0;
  for (double c : counts) cmax = std::max(cmax, c);
  PlotOptions o = options;
  Image im(o.width, o.height);
  const Axes a = MakeAxes(o, l, h, 0, std::max(1.0, cmax));
  DrawFrame(&im, a, o, true);
  for (int b = 0; b < bins; ++b) {
    const double x0 = l + (h - l) * b / bins, x1 = l + (h - l) * (b + 1) / bins;
    if (counts[static_cast<std::size_t>(b)] <= 0) continue;
    FillRect(&im, a.X(x0) + 1, a.Y(counts[static_cast<std::size_t>(b)]), a.X(x1) - 1, a.Y(0),
             Rgb{31, 119, 180});
  }
  return im;
}

}  // namespace pectus::render
