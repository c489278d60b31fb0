#include "datasets/chest_population.h"

#include <Eigen/Dense>
#include <cmath>
#include <random>

#include "shape/core/error.h"

namespace pectus::datasets {
namespace {

// Index of a named linear parameter (LinearPart order).
enum Field : int {
  kWidth = 0,
  kDepth,
  kLength,
  kRecession,
  kRidge,
  kTissue,
  kPectoral,
  kBreast,
  kGroove,
  kConcavity,
  kNotch,
  kClavicle,
  kNamedFieldCount
};

LatentFactor Factor(const char* name, const char* description,
                    std::initializer_list<std::pair<Field, double>> l) {
  LatentFactor f{name, description, Eigen::VectorXd::Zero(kLinearParameterCount)};
  for (const auto& [field, value] : l) f.loading(field) = value;
  return f;
}

}  // namespace

PopulationModel PopulationModel::Default() {
  PopulationModel m;  // ChestParameters' defaults are the population means
  m.mean.detail_mm.resize(0);
  LatentFactor size{"size", "overall size: every length of the chest 7 % larger",
                    Eigen::VectorXd::Zero(kLinearParameterCount)};
  const Eigen::VectorXd mean = LinearPart(m.mean);
  size.loading.head(kNamedFieldCount) = 0.07 * mean.head(kNamedFieldCount);
  m.factors = {
      size,
      Factor("breadth", "wide and flat against narrow and deep", {{kWidth, 18.0}, {kDepth, -12.0}}),
      Factor("height", "long against short sternum", {{kLength, 6.0}}),
      Factor("adiposity", "subcutaneous fat and breasts",
             {{kTissue, 2.5}, {kBreast, 4.0}, {kGroove, -1.0}, {kConcavity, -0.5}}),
      Factor("muscularity", "pectoral muscles, with a deeper sternal groove",
             {{kPectoral, 3.0}, {kGroove, 1.5}, {kConcavity, 0.8}, {kClavicle, 0.8}}),
      Factor("costal", "prominence of the costal margins and recession of the abdomen",
             {{kRecession, 4.0}, {kRidge, 1.2}}),
  };
  return m;
}

bool PopulationModel::IsValid(std::string* why) const {
  auto fail = [&](const std::string& m) {
    if (why) *why = m;
    return false;
  };
  if (!mean.IsValid(why)) return false;
  if (mean.pectus.depth_mm != 0.0) return fail("a population mean must have no pectus excavatum");
  for (const LatentFactor& f : factors) {
    if (f.loading.size() != kLinearParameterCount || !f.loading.allFinite()) {
      return fail("latent factor '" + f.name + "' has a malformed loading");
    }
  }
  if (!(detail_sd_mm >= 0.0) || detail_sd_mm > 10.0) return fail("detail sd must be within [0, 10] mm");
  return true;
}

Eigen::MatrixXd PopulationModel::CovarianceRoot() const {
  const int k = static_cast<int>(factors.size());
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(kLinearParameterCount, k + kDetailCoefficients);
  for (int i = 0; i < k; ++i) A.col(i) = factors[i].loading;
  A.bottomRightCorner(kDetailCoefficients, kDetailCoefficients).diagonal().setConstant(detail_sd_mm);
  return A;
}

SubjectSample SampleSubject(const PopulationModel& population, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  SubjectSample s;
  s.latent.resize(static_cast<Eigen::Index>(population.factors.size()));
  Eigen::VectorXd x = LinearPart(population.mean);
  for (std::size_t k = 0; k < population.factors.size(); ++k) {
    s.latent(static_cast<Eigen::Index>(k)) = normal(rng);
    x += s.latent(static_cast<Eigen::Index>(k)) * population.factors[k].loading;
  }
  for (int i = 0; i < kDetailCoefficients; ++i)
    x(kLinearParameterCount - kDetailCoefficients + i) += population.detail_sd_mm * normal(rng);
  s.parameters = population.mean;
  SetLinearPart(x, &s.parameters);
  return s;
}

Eigen::Vector2d ShapeGrid::At(Eigen::Index k) const {
  const Eigen::Index i = k % nu, j = k / nu;
  return {u0 + (u1 - u0) * static_cast<double>(i) / (nu - 1),
          v0 + (v1 - v0) * static_cast<double>(j) / (nv - 1)};
}

Points3 SampleGrid(const ChestSurface& surface, const ShapeGrid& grid) {
  if (grid.nu < 2 || grid.nv < 2) ThrowUsage("a shape grid needs at least 2 by 2 vertices");
  Points3 X(grid.size(), 3);
  for (Eigen::Index k = 0; k < grid.size(); ++k) {
    const Eigen::Vector2d uv = grid.At(k);
    X.row(k) = surface.Position(uv.x(), uv.y()).transpose();
  }
  return X;
}

TrueShapeStatistics ComputeTrueShapeStatistics(const PopulationModel& population, const ShapeGrid& grid,
                                               int count) {
  std::string why;
  if (!population.IsValid(&why)) ThrowUsage("population: " + why);
  TrueShapeStatistics st;
  st.grid = grid;
  st.mean = SampleGrid(ChestSurface(population.mean), grid);
  const Eigen::MatrixXd A = population.CovarianceRoot();
  const Eigen::VectorXd p0 = LinearPart(population.mean);
  // The surface is affine in the parameters, so column k of A moves the grid by exactly B(:, k).
  const Eigen::Index m = 3 * grid.size();
  Eigen::MatrixXd B(m, A.cols());
#pragma omp parallel for schedule(dynamic)
  for (Eigen::Index k = 0; k < A.cols(); ++k) {
    ChestParameters p = population.mean;
    SetLinearPart(p0 + A.col(k), &p);
    const Points3 X = SampleGrid(ChestSurface(p), grid);
    const Points3 D = X - st.mean;
    B.col(k) = Eigen::Map<const Eigen::VectorXd>(D.data(), m);  // row-major: x1 y1 z1 x2 ...
  }
  // Covariance B B^T: its eigenvectors are B V S^-1 with B^T B = V S^2 V^T.
  // The Gram matrix by explicit dot products: Eigen's matrix product would split the sums over OpenMP
  // threads, and the written statistics must not depend on the thread count.
  Eigen::MatrixXd G(B.cols(), B.cols());
#pragma omp parallel for schedule(dynamic)
  for (Eigen::Index i = 0; i < B.cols(); ++i) {
    for (Eigen::Index j = 0; j <= i; ++j) G(i, j) = G(j, i) = B.col(i).dot(B.col(j));
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(G);
  const Eigen::Index n = eig.eigenvalues().size();
  count = static_cast<int>(std::min<Eigen::Index>(count, n));
  st.total_variance = eig.eigenvalues().sum();
  st.eigenvalues.resize(count);
  st.explained.resize(count);
  st.mode_parameters.resize(kLinearParameterCount, count);
  for (int j = 0; j < count; ++j) {
    const double lambda = eig.eigenvalues()(n - 1 - j);
    const Eigen::VectorXd vj = eig.eigenvectors().col(n - 1 - j);
    const double s = std::sqrt(std::max(lambda, 1e-300));
    Eigen::VectorXd mode = B * vj / s;
    Eigen::VectorXd params = A * vj / s;
    Eigen::Index largest;
    mode.cwiseAbs().maxCoeff(&largest);
    if (mode(largest) < 0.0) {
      mode = -mode;
      params = -params;
    }
    st.eigenvalues(j) = lambda;
    st.explained(j) = lambda / st.total_variance;
    st.modes.push_back(Eigen::Map<const Points3>(mode.data(), grid.size(), 3));
    st.mode_parameters.col(j) = params;
  }
  return st;
}

ChestParameters AlongMode(const PopulationModel& population, const TrueShapeStatistics& statistics, int j,
                          double sd) {
  if (j < 0 || j >= statistics.mode_parameters.cols()) ThrowUsage("no true mode " + std::to_string(j));
  ChestParameters p = population.mean;
  SetLinearPart(LinearPart(population.mean) +
                    sd * std::sqrt(statistics.eigenvalues(j)) * statistics.mode_parameters.col(j),
                &p);
  return p;
}

nlohmann::json PopulationJson(const PopulationModel& population, const TrueShapeStatistics& statistics) {
  nlohmann::json j;
  j["mean_parameters"] = ToJson(population.mean);
  j["detail_sd_mm"] = population.detail_sd_mm;
  nlohmann::json factors = nlohmann::json::array();
  for (const LatentFactor& f : population.factors) {
    nlohmann::json loading = nlohmann::json::object();
    for (int i = 0; i < kLinearParameterCount; ++i) {
      if (f.loading(i) != 0.0) loading[LinearParameterName(i)] = f.loading(i);
    }
    factors.push_back({{"name", f.name}, {"description", f.description}, {"loading_per_sd", loading}});
  }
  j["latent_factors"] = factors;
  const ShapeGrid& g = statistics.grid;
  j["grid"] = {{"nu", g.nu},
               {"nv", g.nv},
               {"u_range", {g.u0, g.u1}},
               {"v_range", {g.v0, g.v1}},
               {"vertex_order", "k = j * nu + i (u index i, v index j)"}};
  j["total_variance_mm2"] = statistics.total_variance;
  j["eigenvalues_mm2"] = std::vector<double>(statistics.eigenvalues.data(),
                                             statistics.eigenvalues.data() + statistics.eigenvalues.size());
  j["explained_fraction"] = std::vector<double>(statistics.explained.data(),
                                                statistics.explained.data() + statistics.explained.size());
  nlohmann::json modes = nlohmann::json::array();
  for (Eigen::Index c = 0; c < statistics.mode_parameters.cols(); ++c) {
    const Eigen::VectorXd col = statistics.mode_parameters.col(c);
    modes.push_back(std::vector<double>(col.data(), col.data() + col.size()));
  }
  j["mode_parameters"] = modes;
  return j;
}

}  // namespace pectus::datasets
