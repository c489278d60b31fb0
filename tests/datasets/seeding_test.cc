// Tests of datasets/seeding.h: derived seeds are distinct per stream and index, and RandomUnit draws
// directions uniformly on the unit sphere (the moments of the uniform distribution: mean 0, E[x x^T] = I/3).
#include "datasets/seeding.h"

#include <gtest/gtest.h>

#include <cmath>
#include <set>

namespace pectus::datasets {
namespace {

TEST(Seeding, DerivedSeedsDifferPerStreamAndIndex) {
  std::set<std::uint64_t> seeds;
  for (SeedStream stream : {SeedStream::kSubject, SeedStream::kScan, SeedStream::kSweep, SeedStream::kPair}) {
    for (std::uint64_t index = 0; index < 100; ++index) seeds.insert(DeriveSeed(7, stream, index));
  }
  EXPECT_EQ(seeds.size(), 400u);
  EXPECT_EQ(DeriveSeed(7, SeedStream::kScan, 3), DeriveSeed(7, SeedStream::kScan, 3));
  EXPECT_NE(DeriveSeed(7, SeedStream::kScan, 3), DeriveSeed(8, SeedStream::kScan, 3));
}

TEST(Seeding, RandomUnitIsUniformOnTheSphere) {
  std::mt19937_64 rng(42);
  const int n = 20000;
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  Eigen::Matrix3d second = Eigen::Matrix3d::Zero();
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d a = RandomUnit(&rng);
    ASSERT_NEAR(a.norm(), 1.0, 1e-12);
    mean += a / n;
    second += a * a.transpose() / n;
  }
  // Uniform on the sphere: each component has mean 0 and variance 1/3, so the sample mean's standard
  // error is sqrt(1/3/n) = 0.0041 and a second moment's about sqrt(4/45/n) = 0.0021: 5 standard errors.
  EXPECT_LT(mean.cwiseAbs().maxCoeff(), 5 * std::sqrt(1.0 / 3.0 / n));
  EXPECT_LT((second - Eigen::Matrix3d::Identity() / 3.0).cwiseAbs().maxCoeff(),
            5 * std::sqrt(4.0 / 45.0 / n));
  // The same generator state gives the same direction.
  std::mt19937_64 a(9), b(9);
  EXPECT_EQ(RandomUnit(&a), RandomUnit(&b));
}

}  // namespace
}  // namespace pectus::datasets
