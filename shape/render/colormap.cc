// pectus: colour maps (OpenCV's viridis and turbo tables; a blue-white-red diverging map) and a colour bar.
#include "shape/render/colormap.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <opencv2/imgproc.hpp>
#include <vector>

namespace pectus::render {
namespace {

using Table = std::array<Rgb, 256>;

Table OpenCvTable(int cv_map) {
  cv::Mat ramp(256, 1, CV_8UC1);
  for (int i = 0; i < 256; ++i) ramp.at<std::uint8_t>(i) = static_cast<std::uint8_t>(i);
  cv::Mat bgr;
  cv::applyColorMap(ramp, bgr, cv_map);
  Table t;
  for (int i = 0; i < 256; ++i) {
    const cv::Vec3b c = bgr.at<cv::Vec3b>(i);
    t[i] = {c[2], c[1], c[0]};
  }
  return t;
}

// Blue (59, 76, 192) - white - red (180, 4, 38), the end colours of Moreland's cool-warm map.
Table DivergingTable() {
  Table t;
  const double blue[3] = {59, 76, 192}, white[3] = {245, 245, 245}, red[3] = {180, 4, 38};
  for (int i = 0; i < 256; ++i) {
    const double s = i / 255.0;
    const double* a = s < 0.5 ? blue : white;
    const double* b = s < 0.5 ? white : red;
    const double u = s < 0.5 ? s * 2 : (s - 0.5) * 2;
    t[i] = {static_cast<std::uint8_t>(std::lround(a[0] + u * (b[0] - a[0]))),
            static_cast<std::uint8_t>(std::lround(a[1] + u * (b[1] - a[1]))),
            static_cast<std::uint8_t>(std::lround(a[2] + u * (b[2] - a[2])))};
  }
  return t;
}

const Table& TableOf(Colormap map) {
  static const Table viridis = OpenCvTable(cv::COLORMAP_VIRIDIS);
  static const Table turbo = OpenCvTable(cv::COLORMAP_TURBO);
  static const Table diverging = DivergingTable();
  switch (map) {
    case Colormap::kViridis: return viridis;
    case Colormap::kTurbo: return turbo;
    case Colormap::kDiverging: return diverging;
  }
  return viridis;
}

// Fewest decimals that write every multiple of `step` exactly: 0 for 5, 1 for 2.5 or 0.5, 2 for 0.25.
std::string FormatTick(double v, double step) {
  int decimals = 0;
  for (double scaled = step; decimals < 6 && std::abs(scaled - std::round(scaled)) > 1e-9 * scaled;
       ++decimals) {
    scaled *= 10.0;
  }
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, std::abs(v) < 0.5 * step ? 0.0 : v);
  return buf;
}

}  // namespace

Rgb MapColor(double value, double lo, double hi, Colormap map) {
  if (!std::isfinite(value)) return kGrey;
  double s = hi > lo ? (value - lo) / (hi - lo) : 0.5;
  s = std::clamp(s, 0.0, 1.0);
  return TableOf(map)[static_cast<std::size_t>(std::lround(s * 255.0))];
}

Colors3 MapColors(const Eigen::VectorXd& values, double lo, double hi, Colormap map) {
  Colors3 c(values.size(), 3);
  for (Eigen::Index i = 0; i < values.size(); ++i) {
    const Rgb k = MapColor(values[i], lo, hi, map);
    c(i, 0) = k.r;
    c(i, 1) = k.g;
    c(i, 2) = k.b;
  }
  return c;
}

Rgb CategoryColor(int index) {
  // The twelve colours of ColorBrewer's "Paired" scheme, reordered so neighbours differ in hue.
  static const Rgb kPalette[12] = {{31, 120, 180},  {227, 26, 28},   {51, 160, 44},   {255, 127, 0},
                                   {106, 61, 154},  {177, 89, 40},   {166, 206, 227}, {251, 154, 153},
                                   {178, 223, 138}, {253, 191, 111}, {202, 178, 214}, {255, 230, 100}};
  const int i = ((index % 12) + 12) % 12;
  return kPalette[i];
}

std::vector<double> NiceTicks(double lo, double hi, int about) {
  if (!(hi > lo) || !std::isfinite(hi - lo)) return {};
  const double raw = (hi - lo) / std::max(1, about - 1);
  const double magnitude = std::pow(10.0, std::floor(std::log10(raw)));
  const auto first = [&](double step) { return static_cast<long long>(std::ceil(lo / step - 1e-9)); };
  const auto last = [&](double step) { return static_cast<long long>(std::floor(hi / step + 1e-9)); };
  double best = 0.0;
  long long best_miss = 0;
  for (const double m : {1.0, 2.0, 2.5, 5.0, 10.0}) {  // ties go to the larger, rounder step
    const double step = m * magnitude;
    const long long miss = std::llabs(last(step) - first(step) + 1 - about);
    if (best == 0.0 || miss <= best_miss) {
      best = step;
      best_miss = miss;
    }
  }
  std::vector<double> ticks;
  for (long long k = first(best); k <= last(best); ++k) ticks.push_back(static_cast<double>(k) * best);
  return ticks;
}

Image ColorBar(double lo, double hi, Colormap map, const std::string& label, int height, int ticks) {
  const int bar_w = 28, top = 30, bottom = 20;
  int label_w = 0, label_h = 0;
  TextSize(label, 0.45, 1, &label_w, &label_h);
  const int width = std::max(120, label_w + 12);  // wide enough for the label
  Image im(width, height, kWhite);
  const int bar_h = height - top - bottom;
  for (int y = 0; y < bar_h; ++y) {
    const double v = hi - (hi - lo) * y / std::max(1, bar_h - 1);
    FillRect(&im, 10, top + y, 10 + bar_w, top + y, MapColor(v, lo, hi, map));
  }
  DrawLine(&im, 10, top, 10 + bar_w, top, kBlack);
  DrawLine(&im, 10, top + bar_h - 1, 10 + bar_w, top + bar_h - 1, kBlack);
  DrawLine(&im, 10, top, 10, top + bar_h - 1, kBlack);
  DrawLine(&im, 10 + bar_w, top, 10 + bar_w, top + bar_h - 1, kBlack);
  // Ticks on round values inside the range; the ends of the range are labelled too unless a round tick
  // sits within a label's height of them.
  const double range = hi - lo;
  if (!(range > 0.0) || !std::isfinite(range)) {
    DrawText(&im, 10 + bar_w + 8, top + bar_h / 2 + 5, FormatTick(lo, 1.0), 0.45);
  } else {
    const std::vector<double> values = NiceTicks(lo, hi, std::max(2, ticks));
    const double step = values.size() >= 2 ? values[1] - values[0] : range;
    const auto y_of = [&](double v) {
      return top + bar_h - 1 - static_cast<int>(std::lround((bar_h - 1) * (v - lo) / range));
    };
    const auto tick = [&](double v) {
      const int y = y_of(v);
      DrawLine(&im, 10 + bar_w, y, 10 + bar_w + 5, y, kBlack);
      DrawText(&im, 10 + bar_w + 8, y + 5, FormatTick(v, step), 0.45);
    };
    const double min_gap = 16.0 * range / std::max(1, bar_h - 1);  // a label's height, in data units
    for (const double v : values) {
      if (v - lo >= min_gap && hi - v >= min_gap) tick(v);
    }
    tick(lo);
    tick(hi);
  }
  DrawText(&im, 4, 20, label, 0.45);
  return im;
}

}  // namespace pectus::render
