// Tests of datasets/synth: subjects are deterministic per seed, pectus draws respect their ranges, placed
// landmarks stay on the skin, growth and pose act as documented, descriptions round-trip.
#include "datasets/synth.h"

#include <gtest/gtest.h>

#include <cmath>

#include "datasets/chest_landmarks.h"
#include "datasets/surface_query.h"
#include "shape/core/error.h"

namespace pectus::datasets {
namespace {

TEST(Synth, SubjectsAreDeterministicPerSeedAndIndex) {
  const SubjectOptions o;
  const SyntheticSubject a = MakeSubject(o, 7, 3), b = MakeSubject(o, 7, 3), c = MakeSubject(o, 7, 4),
                         d = MakeSubject(o, 8, 3);
  EXPECT_EQ(a.name, "subject_003");
  EXPECT_EQ(LinearPart(a.parameters), LinearPart(b.parameters));
  EXPECT_NE(LinearPart(a.parameters), LinearPart(c.parameters));
  EXPECT_NE(LinearPart(a.parameters), LinearPart(d.parameters));
  // Turning the pectus draw or the pose on does not change the population draw of the same subject.
  SubjectOptions with;
  with.pectus.fraction = 1.0;
  with.pose_deg = 20.0;
  EXPECT_EQ(LinearPart(MakeSubject(with, 7, 3).parameters), LinearPart(a.parameters));
}

TEST(Synth, PectusDrawsStayInTheirRanges) {
  SubjectOptions o;
  o.pectus.fraction = 0.5;
  o.pectus.depth_min_mm = 15.0;
  o.pectus.depth_max_mm = 45.0;
  int cases = 0;
  const int n = 200;
  for (int i = 0; i < n; ++i) {
    const PectusParameters& p = MakeSubject(o, 1, i).parameters.pectus;
    if (p.depth_mm == 0.0) continue;
    ++cases;
    EXPECT_GE(p.depth_mm, 15.0);
    EXPECT_LE(p.depth_mm, 45.0);
    EXPECT_LE(std::abs(p.torsion_deg), o.pectus.max_torsion_deg);
    EXPECT_LE(std::abs(p.asymmetry), o.pectus.max_asymmetry);
    EXPECT_LE(std::abs(p.centre_x_mm), o.pectus.max_centre_x_mm);
  }
  // Binomial(200, 0.5): 4 standard deviations is +-28.
  EXPECT_NEAR(cases, n / 2, 28);
}

TEST(Synth, PlacedLandmarksStayOnTheSkinAtTheRequestedError) {
  SubjectOptions o;
  o.pose_deg = 30.0;
  o.pose_mm = 200.0;
  const SyntheticSubject s = MakeSubject(o, 2, 0);
  const ChestSurface skin = s.Skin();
  const LandmarkSet exact = TrueLandmarks(skin);
  double sum2 = 0.0;
  int count = 0;
  for (std::uint64_t seed = 0; seed < 20; ++seed) {
    const LandmarkSet placed = PlaceLandmarks(skin, 3.0, seed);
    for (std::size_t i = 0; i < placed.size(); ++i) {
      EXPECT_LT(ClosestPoint(skin, placed.items[i].position).distance, 1e-6);
      sum2 += (placed.items[i].position - exact.items[i].position).squaredNorm();
      ++count;
    }
  }
  // Two tangential axes of sd 3 mm: RMS displacement 3 sqrt(2) = 4.24 mm (220 draws: within 15 %).
  EXPECT_NEAR(std::sqrt(sum2 / count), 3.0 * std::sqrt(2.0), 0.15 * 4.24);
}

TEST(Synth, PoseMovesTheSubjectRigidly) {
  SubjectOptions posed;
  posed.pose_deg = 40.0;
  posed.pose_mm = 300.0;
  const LandmarkSet a = TrueLandmarks(MakeSubject(SubjectOptions{}, 5, 1).Skin());
  const LandmarkSet b = TrueLandmarks(MakeSubject(posed, 5, 1).Skin());
  for (std::size_t i = 0; i < a.size(); ++i) {
    for (std::size_t j = 0; j < i; ++j) {
      EXPECT_NEAR((a.items[i].position - a.items[j].position).norm(),
                  (b.items[i].position - b.items[j].position).norm(), 1e-9);
    }
  }
  EXPECT_GT((a.items[0].position - b.items[0].position).norm(), 100.0);
}

TEST(Synth, GrowthScalesAboutTheNotch) {
  const SyntheticSubject pre = MakeSubject(SubjectOptions{}, 3, 0);
  GrowthOptions g;
  g.years = 2.0;
  const SyntheticSubject post = GrowSubject(pre, g, "post");
  const LandmarkSet a = TrueLandmarks(pre.Skin()), b = TrueLandmarks(post.Skin());
  const Eigen::Vector3d scale(std::pow(1 + g.width_per_year, 2), std::pow(1 + g.height_per_year, 2),
                              std::pow(1 + g.depth_per_year, 2));
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_LT((b.items[i].position - a.items[i].position.cwiseProduct(scale)).norm(), 1e-9)
        << a.items[i].label;
  }
  EXPECT_EQ(post.origin, "growth of subject_000");
}

TEST(Synth, ScannedSubjectsAreDeterministicAndCarryTheirLandmarks) {
  ScanOptions scan;
  scan.sweeps = 3;
  scan.spacing_mm = 4.0;
  const SyntheticSubject s = MakeSubject(SubjectOptions{}, 4, 2);
  const ScannedSubject a = ScanSubject(s, scan, 2.0, 99), b = ScanSubject(s, scan, 2.0, 99);
  ASSERT_EQ(a.scan.sweeps.size(), 3u);
  for (std::size_t k = 0; k < 3; ++k)
    EXPECT_EQ(a.scan.sweeps[k].cloud.positions, b.scan.sweeps[k].cloud.positions);
  EXPECT_EQ(a.true_landmarks.size(), 11u);
  EXPECT_EQ(a.placed_landmarks.items[0].position, b.placed_landmarks.items[0].position);
  EXPECT_NE(a.placed_landmarks.items[0].position, a.true_landmarks.items[0].position);
}

TEST(Synth, DescriptionRoundTripsExactly) {
  SubjectOptions o;
  o.pectus.fraction = 1.0;
  o.pose_deg = 10.0;
  const SyntheticSubject s = MakeSubject(o, 9, 1);
  const SyntheticSubject r = SubjectFromJson(nlohmann::json::parse(SubjectJson(s).dump()), "round trip");
  EXPECT_EQ(r.name, s.name);
  EXPECT_EQ(r.seed, s.seed);
  EXPECT_EQ(LinearPart(r.parameters), LinearPart(s.parameters));
  EXPECT_EQ(r.parameters.pectus.depth_mm, s.parameters.pectus.depth_mm);
  EXPECT_LT((r.parameters.T_scan_subject.matrix() - s.parameters.T_scan_subject.matrix()).norm(), 1e-12);
  EXPECT_EQ(r.latent, s.latent);
  EXPECT_THROW(SubjectFromJson(nlohmann::json::object(), "empty"), Error);
}

TEST(Synth, RejectsInvalidOptions) {
  SubjectOptions o;
  o.pectus.fraction = 1.5;
  EXPECT_THROW(MakeSubject(o, 1, 0), Error);
  PectusParameters pe;
  pe.depth_mm = 80.0;
  EXPECT_THROW(MakeSubjectWithPectus(SubjectOptions{}, 1, 0, pe), Error);
}

}  // namespace
}  // namespace pectus::datasets
