// Tests of datasets/internal/sweep_path: the sweep patterns, measured on the true points SimulateScan
// makes along them: neighbours share the requested fraction of their area, horizontal strips run across
// the chest, a spiral's turns go outward from the sternum.
#include "datasets/internal/sweep_path.h"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <set>

#include "datasets/chest_population.h"
#include "datasets/scan_simulator.h"
#include "tests/datasets/sample_chest.h"

namespace pectus::datasets::internal {
namespace {

// Clean sweeps: no holes, outliers or thinning, so that a sweep's area is where its laser lines went.
ScanOptions Clean(SweepPattern pattern, int sweeps, double overlap) {
  ScanOptions o;
  o.pattern = pattern;
  o.sweeps = sweeps;
  o.overlap = overlap;
  o.spacing_mm = 2.0;
  o.subject_holes = o.sweep_holes = 0;
  o.outlier_fraction = 0.0;
  o.incidence_falloff = 0.0;
  return o;
}

// The surface area (mm^2) a set of true points covers, on a raster of (u, v) cells about 4 mm square:
// a cell counts (with its area |x_u x x_v| du dv) if a point lies in it. Every region grows by about half
// a cell at its borders, so a shared fraction measured so is biased up by about a cell over the width.
class Raster {
 public:
  static constexpr double kDu = 0.02, kDv = 0.016;
  explicit Raster(const ChestSurface& s) : surface_(s) {}
  std::set<std::pair<int, int>> Cells(const SweepTruth& t) const {
    std::set<std::pair<int, int>> cells;
    for (Eigen::Index i = 0; i < t.u.size(); ++i)
      cells.insert({static_cast<int>(std::floor(t.u(i) / kDu)), static_cast<int>(std::floor(t.v(i) / kDv))});
    return cells;
  }
  double Area(const std::set<std::pair<int, int>>& cells) const {
    double area = 0.0;
    for (const auto& [i, j] : cells) {
      const SurfacePoint p = surface_.Evaluate((i + 0.5) * kDu, (j + 0.5) * kDv);
      area += p.d_du.cross(p.d_dv).norm() * kDu * kDv;
    }
    return area;
  }
  // Area shared by a and b over the area of a.
  double SharedFraction(const std::set<std::pair<int, int>>& a,
                        const std::set<std::pair<int, int>>& b) const {
    std::set<std::pair<int, int>> both;
    for (const auto& c : a)
      if (b.count(c)) both.insert(c);
    return Area(both) / Area(a);
  }

 private:
  const ChestSurface& surface_;
};

// Where two sweeps overlap across `axis` (0: u, 1: v), measured on their true points: rows about 8 mm
// wide along the other axis (4 laser lines of 2 mm); in each row that both reach, each sweep's extent
// [min, max] on `axis`; the overlap is the length both extents share (mm, at the local |x_axis|) over the
// length of a's extent, summed over the rows, in the surface parameter (the overlap is designed in u for
// vertical strips and v for horizontal ones; in mm it differs by the variation of |x_u| or |x_v| across a
// strip, up to 10 % at the flanks). A laser line's end rays hit its borders exactly but are
// kept half as often (the frayed fringe), which shortens a one-line extent; the border's wander lengthens
// a many-line one; over 4 lines the two are within 0.01 of each other (measured at overlap 0.4).
double SharedFraction(const std::vector<const SweepTruth*>& a, const std::vector<const SweepTruth*>& b,
                      int axis) {
  const double row_width = axis == 0 ? 0.03 : 0.04;
  struct Extent {
    double lo = 1e9, hi = -1e9;
  };
  std::map<int, Extent> ea, eb;
  auto add = [&](const std::vector<const SweepTruth*>& sweeps, std::map<int, Extent>* extents) {
    for (const SweepTruth* t : sweeps) {
      for (Eigen::Index i = 0; i < t->u.size(); ++i) {
        const double across = axis == 0 ? t->u(i) : t->v(i), along = axis == 0 ? t->v(i) : t->u(i);
        Extent& e = (*extents)[static_cast<int>(std::floor(along / row_width))];
        e.lo = std::min(e.lo, across);
        e.hi = std::max(e.hi, across);
      }
    }
  };
  add(a, &ea);
  add(b, &eb);
  double shared = 0.0, width = 0.0;
  for (const auto& [row, x] : ea) {
    const auto it = eb.find(row);
    if (it == eb.end()) continue;
    const Extent& y = it->second;
    const double lo = std::max(x.lo, y.lo), hi = std::min(x.hi, y.hi);
    width += x.hi - x.lo;
    if (hi > lo) shared += hi - lo;
  }
  return shared / width;
}

// Neighbouring strips share `overlap` of a strip's width, measured on the true points (ragged borders,
// wandering by up to 6 mm, included): within 0.02 of the requested fraction (0.03 for the outermost
// vertical strips, whose outer edge lies on the flank where grazing rays go unreturned).
TEST(SweepPath, NeighbouringStripsShareTheRequestedFractionOfTheirArea) {
  const ChestSurface surface = SampleChest();
  for (SweepPattern pattern : {SweepPattern::kVertical, SweepPattern::kHorizontal}) {
    const int axis = pattern == SweepPattern::kVertical ? 0 : 1;
    for (double overlap : {0.1, 0.2, 0.4}) {
      const Scan scan = SimulateScan(surface, Clean(pattern, 4, overlap), 3);
      for (std::size_t k = 0; k + 1 < scan.sweeps.size(); ++k) {
        const double tolerance =
            pattern == SweepPattern::kVertical && (k == 0 || k + 2 == scan.sweeps.size()) ? 0.03 : 0.02;
        SCOPED_TRACE(ToString(pattern) + " overlap " + std::to_string(overlap) + " pair " +
                     std::to_string(k));
        const SweepTruth *a = &scan.sweeps[k].truth, *b = &scan.sweeps[k + 1].truth;
        EXPECT_NEAR(SharedFraction({a}, {b}, axis), overlap, tolerance);
        EXPECT_NEAR(SharedFraction({b}, {a}, axis), overlap, tolerance);
      }
    }
  }
}

// Patches: neighbours within a row share `overlap` of a patch's width, and the rows share `overlap` of a
// row's height, within 0.03 as a mean over 4 seeds (a patch's ends, where the rows meet, are ragged by
// +-0.02 in v each, drawn per patch: at overlap 0.1 that is +-40 % of the shared band in one scan).
TEST(SweepPath, NeighbouringPatchesShareTheRequestedFractionOfTheirArea) {
  const ChestSurface surface = SampleChest();
  for (double overlap : {0.1, 0.2, 0.4}) {
    SCOPED_TRACE("overlap " + std::to_string(overlap));
    double across = 0.0, rows = 0.0;
    for (std::uint64_t seed : {5, 6, 7, 8}) {
      const Scan scan =
          SimulateScan(surface, Clean(SweepPattern::kPatches, 6, overlap), seed);  // 2 rows of 3
      std::vector<const SweepTruth*> t;
      for (const Sweep& s : scan.sweeps) t.push_back(&s.truth);
      across += SharedFraction({t[1]}, {t[0]}, 0) + SharedFraction({t[1]}, {t[2]}, 0) +
                SharedFraction({t[4]}, {t[3]}, 0) + SharedFraction({t[4]}, {t[5]}, 0);
      rows += SharedFraction({t[0], t[1], t[2]}, {t[3], t[4], t[5]}, 1);
      EXPECT_GT(t[0]->v.minCoeff(), t[3]->v.minCoeff());  // the top row first
    }
    EXPECT_NEAR(across / 16.0, overlap, 0.03);
    EXPECT_NEAR(rows / 4.0, overlap, 0.03);
  }
}

// Horizontal strips run across the chest: each reaches both flanks (|u| > 0.85), spans a band of v no
// wider than its nominal band and 2 x 8 mm of wander, and the wand goes along u (the laser line's index
// follows u, correlation > 0.98), every other strip back the other way.
TEST(SweepPath, HorizontalStripsRunAcrossTheChest) {
  const ChestSurface surface = SampleChest();
  const Scan scan = SimulateScan(surface, Clean(SweepPattern::kHorizontal, 5, 0.2), 8);
  double previous_v = 2.0;
  for (std::size_t k = 0; k < scan.sweeps.size(); ++k) {
    const Sweep& s = scan.sweeps[k];
    EXPECT_LT(s.truth.u.minCoeff(), -0.85);
    EXPECT_GT(s.truth.u.maxCoeff(), 0.85);
    const double mm_per_v = surface.Evaluate(0.0, 0.5).d_dv.norm();
    EXPECT_LT((s.truth.v.maxCoeff() - s.truth.v.minCoeff()) * mm_per_v,
              (s.truth.strip_v1 - s.truth.strip_v0) * mm_per_v + 16.0);
    const double mean_v = s.truth.v.mean();
    EXPECT_LT(mean_v, previous_v);  // from the top down
    previous_v = mean_v;
    const Eigen::VectorXd& line = s.cloud.scalars.at("line");
    const Eigen::ArrayXd a = line.array() - line.mean(), b = s.truth.u.array() - s.truth.u.mean();
    const double correlation = (a * b).sum() / std::sqrt((a * a).sum() * (b * b).sum());
    EXPECT_GT(correlation * (k % 2 ? -1.0 : 1.0), 0.98);
  }
}

// A spiral: the first turn covers mid-sternum, each turn lies farther out than the one before, and
// neighbouring turns overlap (share at least half the requested fraction of the inner one's area; a
// turn's band is cut where it leaves the chest, so the shared part is not exactly the fraction).
TEST(SweepPath, SpiralTurnsGoOutwardFromTheSternum) {
  const ChestSurface surface = SampleChest();
  const Raster raster(surface);
  const ScanOptions o = Clean(SweepPattern::kSpiral, 4, 0.3);
  const Scan scan = SimulateScan(surface, o, 2);
  const std::vector<SweepPlan> plans = PlanSweeps(o);
  double previous = -1.0;
  for (std::size_t k = 0; k < scan.sweeps.size(); ++k) {
    const SweepTruth& t = scan.sweeps[k].truth;
    const Eigen::ArrayXd q = ((t.u.array() - plans[k].centre_u) / plans[k].radius_u).square() +
                             ((t.v.array() - plans[k].centre_v) / plans[k].radius_v).square();
    const double radius = q.sqrt().mean();
    EXPECT_GT(radius, previous);
    previous = radius;
    if (k == 0) {
      EXPECT_LT(q.sqrt().minCoeff(), 0.02);
    }
    if (k + 1 < scan.sweeps.size()) {
      EXPECT_GT(raster.SharedFraction(raster.Cells(t), raster.Cells(scan.sweeps[k + 1].truth)), 0.15);
    }
  }
}

TEST(SweepPath, PlansCoverTheDomainWithTheRequestedNumberOfSweeps) {
  for (SweepPattern pattern :
       {SweepPattern::kVertical, SweepPattern::kHorizontal, SweepPattern::kPatches, SweepPattern::kSpiral}) {
    for (int n : {1, 3, 5, 8, 12}) {
      ScanOptions o;
      o.pattern = pattern;
      o.sweeps = n;
      o.overlap = 0.1;
      EXPECT_EQ(PlanSweeps(o).size(), static_cast<std::size_t>(n)) << ToString(pattern) << " " << n;
    }
  }
}

}  // namespace
}  // namespace pectus::datasets::internal
