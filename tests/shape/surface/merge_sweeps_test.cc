#include "shape/surface/merge_sweeps.h"

#include <gtest/gtest.h>

#include <random>

#include "registration/pose_error.h"
#include "shape/core/error.h"
#include "shape/io/mesh_io.h"
#include "shape/io/stanford_conf.h"
#include "tests/support/bunny_data.h"
#include "tests/support/require_shared_data.h"

namespace pectus {
namespace {

// A random rigid disturbance: rotation up to max_deg about a random axis, translation up to max_mm.
Rigid3 Disturbance(std::mt19937_64* rng, double max_deg, double max_mm) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Eigen::Vector3d axis(u(*rng), u(*rng), u(*rng));
  Eigen::Vector3d t(u(*rng), u(*rng), u(*rng));
  while (t.norm() > 1.0) t = Eigen::Vector3d(u(*rng), u(*rng), u(*rng));
  const double angle = max_deg * M_PI / 180.0 * std::abs(u(*rng));
  Rigid3 T = Rigid3::Identity();
  T.linear() = Eigen::AngleAxisd(angle, axis.normalized()).toRotationMatrix();
  T.translation() = max_mm * t;
  return T;
}

// The disturbance applied about a point (the sweep's centroid in the world) rather than the origin.
Rigid3 DisturbAbout(std::mt19937_64* rng, double max_deg, double max_mm, const PointCloud& sweep,
                    const Rigid3& T_world_sweep) {
  const Eigen::Vector3d c = T_world_sweep * Eigen::Vector3d(sweep.positions.colwise().mean().transpose());
  Rigid3 D = Disturbance(rng, max_deg, max_mm);
  D.translation() += c - D.linear() * c;
  return D * T_world_sweep;
}

// RMS displacement of a sweep's points between two placements (mm).
double RmsDisplacement(const Points3& points, const Rigid3& a, const Rigid3& b) {
  const Rigid3 d = a * b.inverse();
  double s = 0;
  for (Eigen::Index i = 0; i < points.rows(); ++i) {
    const Eigen::Vector3d x = b * points.row(i).transpose();
    s += (d * x - x).squaredNorm();
  }
  return std::sqrt(s / static_cast<double>(points.rows()));
}

// Strips of a smooth, wavy dome seen from above, each in its own scanner frame.
std::vector<PointCloud> DomeStrips(int strips, std::vector<Rigid3>* T_world_sweep) {
  std::vector<PointCloud> out;
  std::mt19937_64 rng(3);
  std::normal_distribution<double> noise(0.0, 0.05);
  for (int s = 0; s < strips; ++s) {
    const double y0 = -100.0 + 200.0 * s / strips - 15.0, y1 = -100.0 + 200.0 * (s + 1) / strips + 15.0;
    std::vector<Eigen::Vector3d> pts;
    for (double x = -120; x <= 120; x += 1.0) {
      for (double y = y0; y <= y1; y += 1.0) {
        const double z = 60.0 - 0.002 * (x * x + y * y) + 4.0 * std::sin(x / 17.0) * std::cos(y / 23.0 + 0.7);
        pts.emplace_back(x, y, z + noise(rng));
      }
    }
    // The scanner's frame: an arbitrary pose per strip.
    Rigid3 T = Rigid3::Identity();
    T.linear() = Eigen::AngleAxisd(0.3 * s, Eigen::Vector3d(0.2, 1, 0.1).normalized()).toRotationMatrix();
    T.translation() = Eigen::Vector3d(10.0 * s, -5.0 * s, 300.0);
    PointCloud c;
    c.positions.resize(static_cast<Eigen::Index>(pts.size()), 3);
    const Rigid3 T_sweep_world = T.inverse();
    for (std::size_t i = 0; i < pts.size(); ++i)
      c.positions.row(static_cast<Eigen::Index>(i)) = (T_sweep_world * pts[i]).transpose();
    out.push_back(std::move(c));
    T_world_sweep->push_back(T);
  }
  return out;
}

// Starting poses disturbed by up to 3 degrees and 5 mm about each sweep's centroid: a tracker whose stated
// accuracy is that bound.
SweepMergeOptions DisturbedTracker() {
  SweepMergeOptions o;
  o.tracker_deg = 3.0;
  o.tracker_mm = 5.0;
  o.tracker_lever_mm = 0.0;  // the disturbance turns about the centroid
  return o;
}

// The strips carry 0.05 mm noise and overlap in 30 mm bands of 80 mm strips, so the roll of a strip about
// its long axis is known to about 0.02 degrees per link (the data's own limit: more samples of the same
// points do not help); over a chain of three links that is up to ~0.1 mm at a strip's far edge.
constexpr double kStripTolerance = 0.12;

TEST(SweepMerge, RecoversKnownPosesOfSyntheticStrips) {
  std::vector<Rigid3> truth;
  const auto strips = DomeStrips(4, &truth);
  std::mt19937_64 rng(11);
  std::vector<Rigid3> start = truth;
  for (std::size_t s = 1; s < start.size(); ++s) start[s] = DisturbAbout(&rng, 3.0, 5.0, strips[s], truth[s]);
  const SweepMergeResult r = MergeSweeps(strips, start, DisturbedTracker());
  ASSERT_EQ(r.T_world_sweep.size(), 4u);
  // No sweep is held: the common frame is the tracker's average, so the strips are compared with the
  // truth up to one common rigid motion.
  const Rigid3 G = BestCommonMotion(strips, r.T_world_sweep, truth, 10);
  for (std::size_t s = 0; s < strips.size(); ++s) {
    EXPECT_LT(RmsDisplacement(strips[s].positions, G * r.T_world_sweep[s], truth[s]), kStripTolerance)
        << "strip " << s;
    EXPECT_GT(r.correction_mm[s] + r.correction_deg[s], s == 0 ? -1.0 : 0.1) << "the start was disturbed";
  }
  EXPECT_EQ(r.pairs.size(), 3u);  // neighbouring strips overlap, others do not
  for (const auto& p : r.pairs) {
    // The noise of two sweeps, the target's averaged over the plane's points (SweepSurfaceOptions).
    const double plane_points = SweepSurfaceOptions().plane_points;
    EXPECT_NEAR(p.rms_after_mm, 0.05 * std::sqrt(1.0 + 1.0 / plane_points), 0.01)
        << "residuals at the noise level of two sweeps";
    EXPECT_GT(p.rms_before_mm, p.rms_after_mm);
  }
  EXPECT_EQ(r.points_in, r.points_out + r.outliers_removed);
  // Normals of the merged cloud agree across strips (the dome faces +z in the world).
  int up = 0;
  for (Eigen::Index i = 0; i < r.merged.size(); ++i) up += r.merged.normals(i, 2) > 0 ? 1 : -1;
  EXPECT_TRUE(std::abs(up) > 0.98 * r.merged.size()) << up << " of " << r.merged.size();
}

TEST(SweepMerge, FarFromOriginGivesTheSameAnswer) {
  std::vector<Rigid3> truth;
  auto strips = DomeStrips(3, &truth);
  std::mt19937_64 rng(5);
  std::vector<Rigid3> start = truth;
  for (std::size_t s = 1; s < start.size(); ++s) start[s] = DisturbAbout(&rng, 2.0, 3.0, strips[s], truth[s]);
  const SweepMergeResult near = MergeSweeps(strips, start, DisturbedTracker());
  // The same scan with the world frame 10 km away: the same poses up to the shift, to 1 micrometre.
  Rigid3 shift = Rigid3::Identity();
  shift.translation() = Eigen::Vector3d(1e7, -2e6, 5e5);
  std::vector<Rigid3> far_truth, far_start;
  for (std::size_t s = 0; s < strips.size(); ++s) {
    far_truth.push_back(shift * truth[s]);
    far_start.push_back(shift * start[s]);
  }
  const SweepMergeResult far = MergeSweeps(strips, far_start, DisturbedTracker());
  const Rigid3 G = BestCommonMotion(strips, far.T_world_sweep, far_truth, 10);
  for (std::size_t s = 0; s < strips.size(); ++s) {
    EXPECT_LT(RmsDisplacement(strips[s].positions, far.T_world_sweep[s], shift * near.T_world_sweep[s]), 1e-3)
        << s;
    EXPECT_LT(RmsDisplacement(strips[s].positions, G * far.T_world_sweep[s], far_truth[s]), kStripTolerance)
        << s;
  }
}

TEST(SweepMerge, SweepWithoutOverlapIsReportedByNameWithItsDistance) {
  std::vector<Rigid3> truth;
  auto strips = DomeStrips(3, &truth);
  truth[2].translation() += Eigen::Vector3d(0, 0, 500);  // far away from the others
  try {
    MergeSweeps(strips, truth, {}, {"left.ply", "middle.ply", "right.ply"});
    FAIL() << "a sweep that overlaps nothing was merged";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::kFailure);
    const std::string m = e.what();
    EXPECT_NE(m.find("right.ply overlaps no other sweep"), std::string::npos) << m;
    EXPECT_NE(m.find("the nearest, middle.ply, is 4"), std::string::npos) << m;  // ~ 480 mm away
  }
}

// Points of the surface x(u, v) = f(u, v) over [u0, u1] x [v0, v1]: on a 1 mm grid, or as many at
// uniformly random places (unstructured sampling), each with 0.05 mm Gaussian noise per axis.
template <typename Surface>
PointCloud Patch(const Surface& f, double u0, double u1, double v0, double v1, bool random,
                 std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0.0, 0.05);
  std::uniform_real_distribution<double> uu(u0, u1), vv(v0, v1);
  const int nu = int(u1 - u0) + 1, nv = int(v1 - v0) + 1;
  PointCloud c;
  c.positions.resize(nu * nv, 3);
  for (int k = 0; k < nu * nv; ++k) {
    const double u = random ? uu(rng) : u0 + k / nv, v = random ? vv(rng) : v0 + k % nv;
    c.positions.row(k) = (f(u, v) + Eigen::Vector3d(noise(rng), noise(rng), noise(rng))).transpose();
  }
  return c;
}

// Displacement of x by the pose error of sweep 1 relative to sweep 0 (both truths are the identity).
Eigen::Vector3d RelativeMove(const std::vector<Rigid3>& P, const Eigen::Vector3d& x) {
  return (P[0].inverse() * P[1]) * x - x;
}

// Two strips of a plane (z = 0) overlapping in a 30 mm band, each sampled at random: the overlap pins
// the height and the tilts of one strip on the other, not the slide within the plane or the turn about
// its normal.
std::vector<PointCloud> PlaneStrips() {
  auto plane = [](double u, double v) { return Eigen::Vector3d(u, v, 0.0); };
  return {Patch(plane, 0, 100, 0, 100, true, 1), Patch(plane, 70, 170, 0, 100, true, 2)};
}

// A pose of the second plane strip off in all six directions, about the overlap's centre (85, 50, 0).
Rigid3 PlaneStripOffInSixDirections() {
  Rigid3 D = Rigid3::Identity();
  D.linear() = (Eigen::AngleAxisd(0.4 * M_PI / 180, Eigen::Vector3d::UnitZ()) *
                Eigen::AngleAxisd(0.3 * M_PI / 180, Eigen::Vector3d::UnitX()))
                   .toRotationMatrix();
  const Eigen::Vector3d c(85, 50, 0);
  D.translation() = c - D.linear() * c + Eigen::Vector3d(1.2, -0.8, 0.9);
  return D;
}

// Over the overlap band: the height between the strips within 0.02 mm of none (pinned), and their slide
// in the plane within `free_tolerance` of what `D` puts there (free).
void ExpectPinnedHeightAndFreeSlide(const SweepMergeResult& r, const Rigid3& D, double free_tolerance) {
  for (const double x : {72.0, 85.0, 98.0}) {
    for (const double y : {5.0, 50.0, 95.0}) {
      const Eigen::Vector3d p(x, y, 0), expected = RelativeMove({Rigid3::Identity(), D}, p);
      const Eigen::Vector3d after = RelativeMove(r.T_world_sweep, p);
      EXPECT_LT(std::abs(after.z()), 0.02) << "pinned: height at " << x << ", " << y;
      EXPECT_LT((after - expected).head<2>().norm(), free_tolerance)
          << "free: the slide at " << x << ", " << y;
    }
  }
}

// A start off in all six directions: the pinned part is removed, the free part stays where the tracker
// put it.
TEST(SweepMerge, PlaneStripKeepsTheTrackerAlongFreeDirectionsAndRemovesThePinnedError) {
  const Rigid3 D = PlaneStripOffInSixDirections();
  ExpectPinnedHeightAndFreeSlide(MergeSweeps(PlaneStrips(), {Rigid3::Identity(), D}), D, 0.02);
}

// The tracker's readings given apart from the start (SweepMergeOptions::tracker_poses): started at the
// truth and held to readings off in all six directions, the same two plane strips keep the truth along
// what the overlap pins and take the readings along what it leaves free (the prior is centred on the
// readings, not on the start). A reading for each sweep or none.
TEST(SweepMerge, TrackerReadingsApartFromTheStartHoldTheFreeDirections) {
  const std::vector<PointCloud> strips = PlaneStrips();
  const Rigid3 D = PlaneStripOffInSixDirections();
  SweepMergeOptions options;
  options.tracker_poses = {Rigid3::Identity(), D};
  ExpectPinnedHeightAndFreeSlide(MergeSweeps(strips, {Rigid3::Identity(), Rigid3::Identity()}, options), D,
                                 0.05);
  options.tracker_poses = {D};
  try {
    MergeSweeps(strips, {Rigid3::Identity(), Rigid3::Identity()}, options);
    ADD_FAILURE() << "one reading for two sweeps was accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::kUsage);
    EXPECT_NE(e.message().find("one tracker reading per sweep"), std::string::npos) << e.message();
  }
}

// The same on a cylinder (radius 150 mm, axis y): the slide along the axis and the turn about it are
// free; the radial offset and the tilts are pinned.
TEST(SweepMerge, CylinderStripKeepsTheTrackerAlongTheAxisAndAboutIt) {
  auto cylinder = [](double u, double v) {
    return Eigen::Vector3d(150.0 * std::sin(u / 150.0), v, 150.0 * std::cos(u / 150.0));
  };
  const std::vector<PointCloud> strips = {Patch(cylinder, -80, 20, 0, 100, false, 3),
                                          Patch(cylinder, -10, 90, 0, 100, true, 4)};
  Rigid3 D = Rigid3::Identity();
  D.linear() = (Eigen::AngleAxisd(0.5 * M_PI / 180, Eigen::Vector3d::UnitY()) *  // free: about the axis
                Eigen::AngleAxisd(0.3 * M_PI / 180, Eigen::Vector3d::UnitX()))   // pinned: a tilt
                   .toRotationMatrix();
  D.translation() = Eigen::Vector3d(0.0, 1.0, 0.0) + 0.8 * cylinder(5, 0).normalized();  // free + pinned
  const SweepMergeResult r = MergeSweeps(strips, {Rigid3::Identity(), D});
  for (const double u : {-8.0, 5.0, 18.0}) {
    for (const double v : {5.0, 50.0, 95.0}) {
      const Eigen::Vector3d p = cylinder(u, v), radial(p.x() / 150.0, 0.0, p.z() / 150.0);
      const Eigen::Vector3d before = RelativeMove({Rigid3::Identity(), D}, p);
      const Eigen::Vector3d after = RelativeMove(r.T_world_sweep, p);
      EXPECT_LT(std::abs(after.dot(radial)), 0.02) << "pinned: radial offset at " << u << ", " << v;
      const Eigen::Vector3d slide_before = before - before.dot(radial) * radial;
      const Eigen::Vector3d slide_after = after - after.dot(radial) * radial;
      // The priors split the pinned correction (about 1 mm here) between the two sweeps in their own
      // metric, which is not aligned with the pair's free directions, so the free part moves by a
      // fraction of the pinned correction: 0.05-0.14 mm measured with GCC, 0.27 mm with clang + ASan
      // (which directions pass the pinned test in the coarse rounds depends on rounding). Following the
      // normals' noise instead, as a merge without the pinned test does, moved it 0.5-1.4 mm.
      EXPECT_LT((slide_after - slide_before).norm(), 0.4) << "free: slide at " << u << ", " << v;
    }
  }
}

// Exact starting poses: nothing moves by more than the noise allows. The data's own limit for the roll of
// a 240 mm strip on a 30 mm band of 0.05 mm noise is about 0.02 degrees (see kStripTolerance), 0.04 mm at
// its ends; measured 0.019-0.052 mm RMS per strip.
TEST(SweepMerge, ExactPosesStayPut) {
  std::vector<Rigid3> truth;
  const auto strips = DomeStrips(4, &truth);
  const SweepMergeResult r = MergeSweeps(strips, truth);
  for (std::size_t s = 0; s < strips.size(); ++s) {
    EXPECT_LT(RmsDisplacement(strips[s].positions, r.T_world_sweep[s], truth[s]), 0.07) << "strip " << s;
  }
}

// Horizontal strips of a chest-like surface (radius 150 mm across, 600 mm up), 1.5 mm apart on average
// at uniformly random places, 0.2 mm noise along the surface normal (a handheld scanner's), each strip
// 60 mm high reaching 12 mm into the next: the overlap bands pin the slide up the gentle curvature and the
// turn about the vertical only weakly, as a chest's horizontal sweeps are pinned. World frame.
std::vector<PointCloud> ChestLikeStrips(int strips, std::uint64_t seed, double height_mm = 60.0,
                                        double reach_mm = 12.0) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0.0, 0.2);
  std::vector<PointCloud> out;
  for (int s = 0; s < strips; ++s) {
    const double y0 = (height_mm - reach_mm) * s - height_mm / 10.0, y1 = y0 + height_mm;
    std::uniform_real_distribution<double> uu(-110.0, 110.0), vv(y0, y1);
    const int count = int(220.0 * height_mm / (1.5 * 1.5));
    PointCloud c;
    c.positions.resize(count, 3);
    for (int k = 0; k < count; ++k) {
      const double x = uu(rng), y = vv(rng);
      const Eigen::Vector3d n = Eigen::Vector3d(x / 150.0, y / 600.0, 1.0).normalized();
      c.positions.row(k) =
          (Eigen::Vector3d(x, y, -x * x / 300.0 - y * y / 1200.0) + noise(rng) * n).transpose();
    }
    out.push_back(std::move(c));
  }
  return out;
}

// Given exact poses, the overlaps' corrections along the directions they pin are at the noise, far below
// the tracker's stated accuracy: the fitted accuracy is a small fraction of it, and the weakly pinned
// directions, which follow the data's noise (0.1-0.25 mm per pair on the chests) under the stated
// prior, are held. Issue 13: no sweep moves by more than 0.05 mm RMS.
TEST(SweepMerge, FittedTrackerAccuracyHoldsExactPoses) {
  const std::vector<Rigid3> truth(3, Rigid3::Identity());
  for (const std::uint64_t seed : {1, 2}) {
    const std::vector<PointCloud> strips = ChestLikeStrips(3, seed);
    const SweepMergeResult fitted = MergeSweeps(strips, truth);
    SweepMergeOptions stated;
    stated.fit_tracker_accuracy = false;
    const SweepMergeResult unfitted = MergeSweeps(strips, truth, stated);
    double worst = 0.0, worst_unfitted = 0.0;
    for (std::size_t s = 0; s < strips.size(); ++s) {
      worst = std::max(worst, RmsDisplacement(strips[s].positions, fitted.T_world_sweep[s], truth[s]));
      worst_unfitted =
          std::max(worst_unfitted, RmsDisplacement(strips[s].positions, unfitted.T_world_sweep[s], truth[s]));
    }
    // Measured 0.017 and 0.007 mm (refits searching correspondences afresh; 0.029 and 0.028 mm with the
    // stated prior on these strips, which pin better than the chests), the fitted accuracy at
    // its floor, 0.01 of the stated.
    EXPECT_LT(worst, 0.05) << "seed " << seed;
    EXPECT_LE(worst, worst_unfitted + 1e-3) << "seed " << seed;
    EXPECT_GT(fitted.tracker_accuracy_factor, 0.0);
    EXPECT_LT(fitted.tracker_accuracy_factor, 0.3);
    EXPECT_EQ(unfitted.tracker_accuracy_factor, 0.0);
  }
}

// Eight narrow strips (40 mm high, reaching 6 mm, 15 %, into the next) pin their poses so weakly that the
// data's own noise moves them along the directions they do pin by a good part of the tracker's error the
// fit estimates from those moves. Read as tracker error, that noise kept the fitted accuracy at 0.017 of
// the stated and let the weakly pinned directions follow it: the worst strip moved 0.054 mm. The fit now
// takes the noise's expected share off (the covariance the data's noise gives the poses, from the joint
// step's information): exact poses read as an exact tracker, the fitted accuracy is at its floor (0.01),
// and the worst strip moves 0.029 mm (GCC 12, Release).
TEST(SweepMerge, FittedTrackerAccuracyTakesTheDataNoiseOff) {
  const std::vector<Rigid3> truth(8, Rigid3::Identity());
  const std::vector<PointCloud> strips = ChestLikeStrips(8, 4, 40.0, 6.0);
  const SweepMergeResult r = MergeSweeps(strips, truth);
  double worst = 0.0;
  for (std::size_t s = 0; s < strips.size(); ++s)
    worst = std::max(worst, RmsDisplacement(strips[s].positions, r.T_world_sweep[s], truth[s]));
  EXPECT_LT(worst, 0.05);
  EXPECT_GT(r.tracker_accuracy_factor, 0.0);
  EXPECT_LE(r.tracker_accuracy_factor, 0.0101) << "the fitted accuracy at its floor";
}

// Three random strips 36 mm high reaching 5 mm (14 %) into each other; the tracker slid the first 4.5 mm
// away from the second, across their band, leaving 0.5 mm of it at the start (1.4 % of the strip). The
// merge links them all the same (at the start a sample within the tracker's error of the other's edge
// counts), and the overlaps then pull what they pin: the first strip ends nearer its truth than it started.
// Before, it was refused as overlapping nothing.
TEST(SweepMerge, ASweepTheTrackerSlidOffANarrowOverlapIsStillLinked) {
  const std::vector<Rigid3> truth(3, Rigid3::Identity());
  const std::vector<PointCloud> strips = ChestLikeStrips(3, 5, 36.0, 5.0);
  std::vector<Rigid3> start = truth;
  start[0].translation() = Eigen::Vector3d(0.0, -4.5, 0.0);  // strip 0 lies below strip 1 (y)
  const SweepMergeResult r = MergeSweeps(strips, start, {}, {"top.ply", "middle.ply", "bottom.ply"});
  bool linked = false;
  for (const SweepPairReport& p : r.pairs) linked = linked || (p.i == 0 && p.j == 1);
  EXPECT_TRUE(linked) << r.message;
  const Rigid3 G = BestCommonMotion(strips, r.T_world_sweep, truth, 10);
  EXPECT_LT(RmsDisplacement(strips[0].positions, G * r.T_world_sweep[0], truth[0]),
            RmsDisplacement(strips[0].positions, start[0], truth[0]));
}

// A tracker about as bad as it states: the fit keeps the prior near its stated accuracy (or leaves it)
// and the error is removed as before. Measured: the fitted accuracy 0.59 of the stated (the disturbance
// draws magnitudes up to the stated values), each strip 0.37-0.62 mm from the truth after 1.7-2.3 mm.
TEST(SweepMerge, FittedTrackerAccuracyKeepsAStatedError) {
  const std::vector<Rigid3> truth(3, Rigid3::Identity());
  const std::vector<PointCloud> strips = ChestLikeStrips(3, 3);
  std::mt19937_64 rng(8);
  std::vector<Rigid3> start;
  SweepMergeOptions o;  // the default prior: 0.5 degrees, 1.5 mm, lever 200 mm
  for (std::size_t s = 0; s < strips.size(); ++s)
    start.push_back(DisturbAbout(&rng, 0.5, 2.3, strips[s], truth[s]));
  const SweepMergeResult r = MergeSweeps(strips, start, o);
  const Rigid3 G = BestCommonMotion(strips, r.T_world_sweep, truth, 10);
  for (std::size_t s = 0; s < strips.size(); ++s) {
    EXPECT_LT(RmsDisplacement(strips[s].positions, G * r.T_world_sweep[s], truth[s]),
              0.5 * RmsDisplacement(strips[s].positions, G * start[s], truth[s]))
        << "strip " << s;
  }
  EXPECT_TRUE(r.tracker_accuracy_factor == 0.0 ||
              (r.tracker_accuracy_factor > 0.3 && r.tracker_accuracy_factor <= 3.0))
      << r.tracker_accuracy_factor;
}

TEST(SweepMerge, SmoothingBlendsOffsetSweepsAndDecimationSetsSpacing) {
  // Two copies of the same plane patch 0.4 mm apart: blending pulls them onto one surface.
  PointCloud a, b;
  std::vector<Eigen::Vector3d> pts;
  for (double x = 0; x < 60; x += 0.7)
    for (double y = 0; y < 60; y += 0.7) pts.emplace_back(x, y, 0);
  a.positions.resize(static_cast<Eigen::Index>(pts.size()), 3);
  for (std::size_t i = 0; i < pts.size(); ++i)
    a.positions.row(static_cast<Eigen::Index>(i)) = pts[i].transpose();
  b.positions = a.positions;
  b.positions.col(2).array() += 0.4;
  b.positions.col(0).array() += 0.35;
  SweepMergeOptions o;
  o.refine_poses = false;
  o.smoothing_mm = 3.0;
  o.target_spacing_mm = 2.0;
  const SweepMergeResult r = MergeSweeps({a, b}, {Rigid3::Identity(), Rigid3::Identity()}, o);
  const double zmax = r.merged.positions.col(2).maxCoeff(), zmin = r.merged.positions.col(2).minCoeff();
  EXPECT_NEAR(0.5 * (zmax + zmin), 0.2, 0.03);
  EXPECT_LT(zmax - zmin, 0.1) << "blended sweeps should meet in the middle";
  // Decimation: about one point per 2 mm voxel over 60 x 60 mm.
  EXPECT_NEAR(static_cast<double>(r.points_out), 30.0 * 30.0, 120.0);
}

TEST(SweepMerge, RealBunnyFromDisturbedPosesReturnsToPublishedPlacement) {
  PECTUS_REQUIRE_SHARED_FILE(testing_support::kBunnyConf);
  const testing_support::BunnySweeps bunny = testing_support::ReadBunnySweeps();
  const std::vector<ScanPose>& poses = bunny.poses;
  const std::vector<PointCloud>& sweeps = bunny.sweeps;
  const std::vector<Rigid3>& truth = bunny.placements;
  std::vector<Rigid3> start;
  std::mt19937_64 rng(2026);
  // Every sweep disturbed about its centroid: up to 3 degrees and 5 mm.
  for (std::size_t s = 0; s < sweeps.size(); ++s)
    start.push_back(DisturbAbout(&rng, 3.0, 5.0, sweeps[s], truth[s]));
  const SweepMergeResult r = MergeSweeps(sweeps, start, DisturbedTracker());
  // Every sweep started disturbed, so the merged set is compared with bun.conf up to one common rigid
  // motion.
  const Rigid3 G = BestCommonMotion(sweeps, r.T_world_sweep, truth, 10);
  for (std::size_t s = 0; s < sweeps.size(); ++s) {
    EXPECT_LE(RmsDisplacement(sweeps[s].positions, G * r.T_world_sweep[s], truth[s]), 0.3) << poses[s].file;
    EXPECT_GE(RmsDisplacement(sweeps[s].positions, G * start[s], truth[s]), s == 0 ? 0.0 : 0.3)
        << "disturbed";
  }
  // Every linked pair's residual near the scanner's noise. Since issue 13 pairs are linked on their
  // geometry from 5 % of shared area, so fringe pairs (ear_back, top2/top3, bun180) that meet where the
  // bunny's sweeps disagree most are in too: 0.31-0.36 mm measured for them, the others under 0.3.
  for (const auto& p : r.pairs) {
    EXPECT_LT(p.rms_after_mm, 0.4) << p.i << "-" << p.j << ", overlap " << p.overlap_fraction;
  }
}

}  // namespace
}  // namespace pectus
