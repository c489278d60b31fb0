#include "shape/surface/internal/cloud_scales.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "registration/kdtree.h"
#include "shape/surface/internal/sparse_grid.h"

namespace pectus {
namespace {

// splitmix64: a fixed pseudo-random number for each index.
std::uint64_t Mix(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

}  // namespace

// A dense cloud is measured on a random subset of about 32k points (each point kept with the same
// probability, so the subset samples the same surface evenly, at a density lower by the kept fraction f):
// s = s_subset * sqrt(f). O(N) for the subset, then O(32k log 32k).
double PointSpacing(const Points3& points) {
  constexpr int k = 16;
  constexpr std::uint64_t kSubset = 32768;
  const auto n = std::uint64_t(points.rows());
  Points3 subset;
  const Points3* p = &points;
  if (n > 2 * kSubset) {
    std::vector<Eigen::Index> kept;
    kept.reserve(std::size_t(kSubset + kSubset / 8));
    for (std::uint64_t i = 0; i < n; ++i)
      if (Mix(i) % n < kSubset) kept.push_back(Eigen::Index(i));
    subset = points(kept, Eigen::all);
    p = &subset;
  }
  const KdTree3 tree(*p);
  const Eigen::Index m = p->rows();
  const Eigen::Index samples = std::min<Eigen::Index>(m, 512);
  std::vector<double> s(static_cast<std::size_t>(samples));
#pragma omp parallel for schedule(static)
  for (Eigen::Index i = 0; i < samples; ++i) {
    std::uint32_t idx[k + 1];
    double d2[k + 1];
    const int found = tree.Knn(p->row(i * m / samples).transpose(), k + 1, idx, d2);
    s[static_cast<std::size_t>(i)] = std::sqrt(d2[found - 1] * M_PI / double(found - 1));
  }
  std::nth_element(s.begin(), s.begin() + samples / 2, s.end());
  return s[static_cast<std::size_t>(samples / 2)] * std::sqrt(double(m) / double(n));
}

// One pass over the points: each adds to the sums (count, sum x, sum x x^T) of its cube if that cube is
// one of the sampled ones (a hash look-up), so the cost is O(N) without a k-d tree.
double NoiseLevel(const Points3& points, double spacing) {
  const Eigen::Index n = points.rows();
  const double side = 4.5 * spacing;
  const Bounds3 b = ComputeBounds(points);
  CheckGridFits(b.extent().maxCoeff() + side, side, "noise level grid");
  auto key_of = [&](Eigen::Index i) {
    const Eigen::Vector3d u = (points.row(i).transpose() - b.min) / side;
    return PackGridKey(std::int64_t(u.x()), std::int64_t(u.y()), std::int64_t(u.z()));
  };
  const Eigen::Index samples = std::min<Eigen::Index>(n, 512);
  GridKeyMap<std::int32_t> sampled(std::size_t(2 * samples));
  for (Eigen::Index i = 0; i < samples; ++i) {
    const auto next = std::int32_t(sampled.size());
    sampled.Insert(key_of(Eigen::Index(Mix(std::uint64_t(i)) % std::uint64_t(n))), next);
  }
  struct Sums {
    double count = 0.0;
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    Eigen::Matrix3d outer = Eigen::Matrix3d::Zero();
    Eigen::Vector3d first = Eigen::Vector3d::Zero();  // sums are taken about a point of the cube
  };
  std::vector<Sums> sums(sampled.size());
  for (Eigen::Index i = 0; i < n; ++i) {
    const std::int32_t* slot = sampled.Find(key_of(i));
    if (slot == nullptr) continue;
    Sums& c = sums[std::size_t(*slot)];
    if (c.count == 0.0) c.first = points.row(i).transpose();
    const Eigen::Vector3d d = points.row(i).transpose() - c.first;
    c.count += 1.0;
    c.sum += d;
    c.outer += d * d.transpose();
  }
  std::vector<double> rms;
  for (const Sums& c : sums) {
    if (c.count < 10.0) continue;
    const Eigen::Vector3d mean = c.sum / c.count;
    const Eigen::Matrix3d cov = c.outer / c.count - mean * mean.transpose();
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig;
    eig.computeDirect(cov, Eigen::EigenvaluesOnly);
    rms.push_back(std::sqrt(std::max(0.0, eig.eigenvalues()(0))));
  }
  if (rms.empty()) return 0.0;
  std::nth_element(rms.begin(), rms.begin() + std::ptrdiff_t(rms.size() / 2), rms.end());
  return rms[rms.size() / 2];
}

}  // namespace pectus
