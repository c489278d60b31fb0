// merge_bias_benchmark: its flags, one correspondence with its truth, and the small statistics the probe
// reports (PCA normals, distances to a sweep's border, RMS and median, eigenvalue bands).
#pragma once

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <string>
#include <vector>

#include "shape/core/geometry.h"
#include "shape/surface/sweep_surface.h"
#include "tests/benchmarks/merge_grid_benchmark_flags.h"

namespace pectus::merge_bias {

struct Flags {
  std::vector<double> overlap = {0.15, 0.2};
  std::vector<std::string> sampling = {"grid", "random"};
  int sweeps = 5, seeds = 3, seed = 1;
  std::string pattern = "horizontal";
  double spacing_mm = 1.5, block_mm = 10.0, border_mm = 5.0;
};

inline Flags Parse(int argc, char** argv) {
  Flags f;
  for (int a = 1; a + 1 < argc; a += 2) {
    const std::string key = argv[a], value = argv[a + 1];
    if (key == "--overlap") {
      f.overlap.clear();
      for (const auto& s : merge_grid::Words(value)) f.overlap.push_back(std::stod(s));
    } else if (key == "--sampling") {
      f.sampling = merge_grid::Words(value);
    } else if (key == "--sweeps") {
      f.sweeps = std::stoi(value);
    } else if (key == "--seeds") {
      f.seeds = std::stoi(value);
    } else if (key == "--seed") {
      f.seed = std::stoi(value);
    } else if (key == "--pattern") {
      f.pattern = value;
    } else if (key == "--spacing") {
      f.spacing_mm = std::stod(value);
    } else if (key == "--block-mm") {
      f.block_mm = std::stod(value);
    } else if (key == "--border-mm") {
      f.border_mm = std::stod(value);
    } else {
      std::fprintf(stderr, "unknown flag %s\n", key.c_str());
      std::exit(2);
    }
  }
  return f;
}

// One correspondence with its truth, in the scan frame.
struct Probe {
  std::size_t i = 0, j = 0;
  Eigen::Vector3d p, q, n;  // as the merge sees them (noisy points, estimated normal)
  Eigen::Vector3d p_true, q_true, n_true;
  Eigen::Vector3d centroid;    // of q's normal neighbourhood (k = 16, q included)
  Eigen::Vector3d n_loo;       // PCA normal of q's 16 nearest neighbours other than q
  Eigen::Vector3d m;           // the source sweep's normal at p (its own noise, independent of q's)
  Eigen::Vector3d p_centroid;  // of p's normal neighbourhood in its own sweep
  Eigen::Vector3d m_loo;       // the source sweep's normal at p fitted without p
  bool near_border = false;
};

// PCA normal (smallest eigenvector) and centroid of rows of `points`.
inline void Pca(const Points3& points, const std::uint32_t* rows, int count, Eigen::Vector3d* normal,
                Eigen::Vector3d* centroid) {
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  for (int k = 0; k < count; ++k) c += points.row(rows[k]).transpose() / double(count);
  Eigen::Matrix3d C = Eigen::Matrix3d::Zero();
  for (int k = 0; k < count; ++k) {
    const Eigen::Vector3d d = points.row(rows[k]).transpose() - c;
    C += d * d.transpose();
  }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> e(C);
  *normal = e.eigenvectors().col(0);
  *centroid = c;
}

// Distance from every point of a sweep to its nearest border point (mm), capped at `cap`.
inline std::vector<double> BorderDistance(const Points3& world, const SweepSurface& s, double cap) {
  std::vector<Eigen::Index> rows;
  for (std::size_t r = 0; r < s.border.size(); ++r)
    if (s.border[r]) rows.push_back(Eigen::Index(r));
  std::vector<double> d(std::size_t(world.rows()), cap);
  if (rows.empty()) return d;
  Points3 b(Eigen::Index(rows.size()), 3);
  for (std::size_t k = 0; k < rows.size(); ++k) b.row(Eigen::Index(k)) = world.row(rows[k]);
  const KdTree3 tree(b);
  for (Eigen::Index r = 0; r < world.rows(); ++r) {
    std::uint32_t k = 0;
    double d2 = 0;
    if (tree.Nearest(world.row(r).transpose(), &k, &d2)) d[std::size_t(r)] = std::min(cap, std::sqrt(d2));
  }
  return d;
}

struct Accumulator {
  std::map<std::string, std::vector<double>> values;
  void Add(const std::string& key, double x) { values[key].push_back(x); }
};

inline double Rms(const std::vector<double>& v) {
  double s = 0;
  for (double x : v) s += x * x;
  return v.empty() ? 0.0 : std::sqrt(s / double(v.size()));
}

inline double Median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::nth_element(v.begin(), v.begin() + std::ptrdiff_t(v.size() / 2), v.end());
  return v[v.size() / 2];
}

inline std::string Band(double lambda) {
  if (lambda < 4) return "lambda<4";
  if (lambda < 30) return "4-30";
  if (lambda < 300) return "30-300";
  if (lambda < 3000) return "300-3000";
  return ">=3000";
}

}  // namespace pectus::merge_bias
