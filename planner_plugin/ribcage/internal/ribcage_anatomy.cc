#include "planner_plugin/ribcage/internal/ribcage_anatomy.h"

#include <utility>

namespace pectus::planner {

const SmoothProfile& SternumWidth() {
  static const SmoothProfile p({{0.0, 48},
                                {0.07, 56},
                                {0.16, 52},
                                {0.29, 30},
                                {0.40, 30},
                                {0.70, 36},
                                {0.86, 30},
                                {0.90, 22},
                                {0.96, 14},
                                {1.0, 8}});
  return p;
}
const SmoothProfile& SternumThickness() {
  static const SmoothProfile p({{0.0, 15}, {0.29, 12}, {0.86, 10}, {0.90, 7}, {1.0, 4}});
  return p;
}
ChestShell MakeShell(double tilt_rad) {
  // Half-width a(z) and half-depth b(z) of the rib centre lines.
  SmoothProfile a({{-280, 114},
                   {-240, 120},
                   {-200, 124},
                   {-160, 124},
                   {-120, 120},
                   {-80, 111},
                   {-40, 97},
                   {0, 76},
                   {20, 62},
                   {45, 42}});
  SmoothProfile b({{-280, 74},
                   {-240, 78},
                   {-200, 80},
                   {-160, 80},
                   {-120, 78},
                   {-80, 73},
                   {-40, 66},
                   {0, 55},
                   {20, 46},
                   {45, 34}});
  return ChestShell(tilt_rad, 5.5, std::move(a), std::move(b));
}

}  // namespace pectus::planner
