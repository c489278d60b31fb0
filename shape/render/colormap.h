// pectus: colour maps for scalar fields (distance maps, errors, sweeps) and a colour bar legend.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "shape/core/geometry.h"
#include "shape/render/image.h"

namespace pectus::render {

/// Colour maps. kViridis for magnitudes (perceptually uniform), kDiverging (blue, white, red) for signed
/// values centred on zero, kTurbo for a rainbow that stays readable.
enum class Colormap { kViridis, kDiverging, kTurbo };

/// The colour of `value` on the scale [lo, hi] (clamped; NaN gives grey).
Rgb MapColor(double value, double lo, double hi, Colormap map);
/// One colour per value (#values by 3), for coloured PLY vertices or renders.
Colors3 MapColors(const Eigen::VectorXd& values, double lo, double hi, Colormap map);
/// A distinct colour for category `index` (sweep number, subject, material region), 12 that cycle.
Rgb CategoryColor(int index);

/// Round tick values (1, 2, 2.5 or 5 times a power of ten apart) inside [lo, hi], about `about` of them;
/// empty for an empty or non-finite range.
std::vector<double> NiceTicks(double lo, double hi, int about);

/// A vertical colour bar `height` pixels tall with tick labels and a label, as its own image, to be
/// put beside a render with HStack so two pictures can share one fixed scale.
Image ColorBar(double lo, double hi, Colormap map, const std::string& label, int height = 600, int ticks = 6);

}  // namespace pectus::render
