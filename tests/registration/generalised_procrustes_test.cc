// Generalised Procrustes: known transforms recovered from exact shapes (point sets and labelled
// landmarks, with and without a reference), the mean averaging noise, clear errors.
#include "registration/generalised_procrustes.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <omp.h>

#include <cstring>
#include <random>

#include "registration/pose_error.h"
#include "shape/core/error.h"
#include "shape/core/task_runner.h"
#include "synthetic_chest.h"

namespace pectus {
namespace {

// Exact landmark sets placed by known similarities: GPA recovers T_mean_shape = T_ref T_i^-1 (to 1e-9),
// with and without scale, and the mean is the reference shape.
TEST(GeneralisedProcrustes, RecoversKnownTransforms) {
  for (const bool scale : {false, true}) {
    std::mt19937_64 rng(71);
    std::vector<Similarity3> T;  // base -> shape i
    std::vector<LandmarkSet> shapes;
    for (int i = 0; i < 5; ++i) {
      Similarity3 t = Similarity3::FromRigid(testing::RandomPose(&rng, 30.0, 200.0));
      if (scale) t.scale = 0.9 + 0.05 * i;
      T.push_back(t);
      shapes.push_back(testing::ChestLandmarks(t, 0.0, 0));
    }
    ProcrustesOptions o;
    o.estimate_scale = scale;
    o.reference = 2;
    const LandmarkProcrustesResult r = GeneralisedProcrustes(shapes, o);
    EXPECT_TRUE(r.converged);
    EXPECT_LT(r.rms_mm, 1e-9);
    for (int i = 0; i < 5; ++i) {
      const Similarity3 expected = T[2] * T[static_cast<std::size_t>(i)].Inverse();
      const PoseError e = ComparePoses(r.T_mean_shape[static_cast<std::size_t>(i)], expected,
                                       shapes[static_cast<std::size_t>(i)].items[0].position);
      EXPECT_LT(e.rotation_deg, 1e-9) << i;
      EXPECT_LT(e.translation_mm, 1e-9) << i;
      EXPECT_NEAR(e.scale_ratio, 1.0, 1e-12) << i;
    }
    for (std::size_t k = 0; k < r.mean.size(); ++k) {
      EXPECT_LT((r.mean.items[k].position - shapes[2].items[k].position).norm(), 1e-9);
    }
  }
}

// With noise the mean lies closer to the noise-free shape than any single noisy shape does on average.
TEST(GeneralisedProcrustes, MeanAveragesNoise) {
  std::vector<LandmarkSet> shapes;
  for (int i = 0; i < 20; ++i)
    shapes.push_back(testing::ChestLandmarks({}, 3.0, 100 + static_cast<std::uint64_t>(i)));
  const LandmarkProcrustesResult r = GeneralisedProcrustes(shapes);
  const LandmarkSet truth = testing::ChestLandmarks({}, 0.0, 0);
  std::vector<LandmarkSet> mean_only = {r.mean, truth};
  const LandmarkProcrustesResult fit = GeneralisedProcrustes(mean_only);
  EXPECT_LT(fit.rms_mm, 1.5);  // single shapes: about 3 * sqrt(3) = 5.2 mm from the truth
}

TEST(GeneralisedProcrustes, TooFewCommonLabelsIsAClearError) {
  LandmarkSet a = testing::ChestLandmarks({}, 0.0, 0), b = a;
  b.items.resize(2);
  try {
    GeneralisedProcrustes({a, b});
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::kBadInput);
    EXPECT_THAT(e.what(), ::testing::HasSubstr("need at least 3"));
  }
}

// Point sets with no reference: exact rigid copies of one shape, so every T_mean_shape[i] * T_i is one
// and the same transform (the floating mean's frame relative to the base shape), and each aligned copy
// lies on the mean. 1e-9 mm: shapes of size 200 mm, Umeyama in doubles.
TEST(GeneralisedProcrustes, FloatingMeanOfRigidCopiesIsTheShape) {
  std::mt19937_64 rng(5);
  const Points3 base = testing::SampleChest(200, 3, 0.0).positions;
  std::vector<Similarity3> T;
  std::vector<Points3> shapes;
  for (int i = 0; i < 4; ++i) {
    T.push_back(Similarity3::FromRigid(testing::RandomPose(&rng, 20.0, 50.0)));
    shapes.push_back(T.back().Apply(base));
  }
  ProcrustesOptions o;
  o.reference.reset();
  o.max_iterations = 3;
  o.tolerance_mm = 0.0;  // all rounds
  const ProcrustesResult r = GeneralisedProcrustes(shapes, o);
  EXPECT_EQ(r.iterations, 3);
  EXPECT_FALSE(r.converged);
  EXPECT_LT(r.rms_mm, 1e-9);
  const Similarity3 first = r.T_mean_shape[0] * T[0];
  for (std::size_t i = 0; i < shapes.size(); ++i) {
    EXPECT_LT(((r.T_mean_shape[i] * T[i]).Matrix() - first.Matrix()).norm(), 1e-9) << i;
    EXPECT_LT((r.T_mean_shape[i].Apply(shapes[i]) - r.mean_points).rowwise().norm().maxCoeff(), 1e-9);
  }
}

// The shapes' alignments are shared out in blocks fixed by their number, and each mean adds the blocks'
// sums in block order: one thread or four, the same bits (as on any number of MPI ranks: the pipeline's
// cluster tests). 70 noisy copies: 9 blocks of 8 and one of 6.
TEST(GeneralisedProcrustes, TheBitsDoNotDependOnTheThreads) {
  std::mt19937_64 rng(11);
  std::normal_distribution<double> noise(0.0, 0.5);
  const Points3 base = testing::SampleChest(300, 3, 0.0).positions;
  std::vector<Points3> shapes;
  for (int i = 0; i < 70; ++i) {
    Points3 x = Similarity3::FromRigid(testing::RandomPose(&rng, 10.0, 30.0)).Apply(base);
    for (Eigen::Index k = 0; k < x.size(); ++k) x.data()[k] += noise(rng);
    shapes.push_back(std::move(x));
  }
  ProcrustesOptions o;
  o.reference.reset();
  o.max_iterations = 4;
  o.tolerance_mm = 0.0;
  SerialTaskRunner runner;
  const int threads = omp_get_max_threads();
  omp_set_num_threads(1);
  const ProcrustesResult one = GeneralisedProcrustes(shapes, o, {}, &runner);
  omp_set_num_threads(4);
  const ProcrustesResult four = GeneralisedProcrustes(shapes, o, {}, &runner);
  omp_set_num_threads(threads);
  ASSERT_EQ(one.mean_points.size(), four.mean_points.size());
  EXPECT_EQ(
      std::memcmp(one.mean_points.data(), four.mean_points.data(), sizeof(double) * one.mean_points.size()),
      0);
  for (std::size_t i = 0; i < shapes.size(); ++i) {
    EXPECT_EQ(one.T_mean_shape[i].Matrix(), four.T_mean_shape[i].Matrix()) << i;
  }
  EXPECT_EQ(one.rms_mm, four.rms_mm);
  EXPECT_GT(one.rms_mm, 0.3);  // the noise is there: sqrt(3) 0.5 mm per point less what the pose absorbs
  EXPECT_LT(one.rms_mm, 1.0);
}

TEST(GeneralisedProcrustes, ShapesOfDifferentSizesAreAClearError) {
  std::vector<Points3> shapes = {Points3::Random(10, 3), Points3::Random(11, 3)};
  try {
    GeneralisedProcrustes(shapes, {}, {"a.ply", "b.ply"});
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::kBadInput);
    EXPECT_THAT(e.what(), ::testing::HasSubstr("b.ply"));
  }
}

}  // namespace
}  // namespace pectus
