#include "shape/model/impute_missing_vertices.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <sstream>
#include <utility>

#include "shape/core/error.h"
#include "shape/core/task_runner.h"

namespace pectus {

bool ImputationOptions::IsValid(std::string* why) const {
  auto fail = [&](const std::string& m) {
    if (why != nullptr) *why = m;
    return false;
  };
  if (max_iterations < 1) return fail("imputation needs at least 1 iteration");
  if (max_others < 2) return fail("the imputation's model of the others needs at least 2 subjects");
  if (!(tolerance_mm > 0.0) || !std::isfinite(tolerance_mm))
    return fail("imputation tolerance must be > 0 mm");
  if (!(noise_mm > 0.0) || !std::isfinite(noise_mm)) return fail("imputation noise must be > 0 mm");
  if (!(local_scale_mm >= 0.0) || !std::isfinite(local_scale_mm))
    return fail("the local correction's length scale must be >= 0 mm");
  if (!(local_sd_mm > 0.0) || !std::isfinite(local_sd_mm))
    return fail("the local correction's standard deviation must be > 0 mm");
  if (!(min_seen_fraction > 0.0 && min_seen_fraction <= 1.0))
    return fail("the least seen fraction for imputation must be in (0, 1]");
  return true;
}

namespace {

// The unseen coordinates (3 per unseen vertex) of subject n.
std::vector<Eigen::Index> UnseenCoordinates(const Eigen::Matrix<bool, Eigen::Dynamic, Eigen::Dynamic>& seen,
                                            Eigen::Index n) {
  std::vector<Eigen::Index> c;
  for (Eigen::Index v = 0; v < seen.cols(); ++v) {
    if (!seen(n, v)) c.insert(c.end(), {3 * v, 3 * v + 1, 3 * v + 2});
  }
  return c;
}

// The model of the others for subject n, from the Gram matrix G = X X' of the current fills: the others'
// rows, their mean, and the weights w of the posterior mean mu + Xc' w (header).
struct Posterior {
  std::vector<Eigen::Index> others;
  Eigen::VectorXd w;
  double inv = 0.0;  // 1 / N'
  // The posterior mean of coordinate c.
  double Mean(const Eigen::MatrixXd& X, Eigen::Index c) const {
    double mu = 0.0;
    for (Eigen::Index a : others) mu += X(a, c);
    mu *= inv;
    double v = mu;
    for (std::size_t a = 0; a < others.size(); ++a)
      v += (X(others[a], c) - mu) * w[static_cast<Eigen::Index>(a)];
    return v;
  }
};

// G = X_S X_S' is the core's Gram matrix (S: the first max_others + 1 rows; every row for a cohort that
// small) and g = X_S x_n, subject n's column of X_S X'.
Posterior PosteriorFromOthers(const Eigen::MatrixXd& X, const Eigen::MatrixXd& G, const Eigen::VectorXd& g,
                              Eigen::Index n, const std::vector<Eigen::Index>& unseen, double noise_variance,
                              int max_others) {
  Posterior post;
  for (Eigen::Index k = 0; k < G.rows() && static_cast<int>(post.others.size()) < max_others; ++k)
    if (k != n) post.others.push_back(k);
  const auto others = static_cast<Eigen::Index>(post.others.size());
  const std::vector<Eigen::Index>& idx = post.others;
  const auto inv = post.inv = 1.0 / static_cast<double>(others);
  // Centring among the others, in subject space: Gc = P G_oo P with P = I - 1 1' / N'.
  Eigen::MatrixXd Goo(others, others);
  Eigen::VectorXd gon(others);  // X_o x_n
  for (Eigen::Index a = 0; a < others; ++a) {
    gon[a] = g[idx[a]];
    for (Eigen::Index b = 0; b < others; ++b) Goo(a, b) = G(idx[a], idx[b]);
  }
  const Eigen::VectorXd row_mean = Goo.rowwise().sum() * inv;  // X_o mu
  const double mean_mean = row_mean.sum() * inv;               // mu' mu
  const double mean_x = gon.sum() * inv;                       // mu' x_n
  Eigen::MatrixXd A = Goo;
  A.colwise() -= row_mean;
  A.rowwise() -= row_mean.transpose();
  A.array() += mean_mean;
  // Xc (x_n - mu) over all coordinates: X_o x_n - X_o mu - 1 mu' x_n + 1 mu' mu.
  Eigen::VectorXd rhs = gon - row_mean;
  rhs.array() += mean_mean - mean_x;
  // Remove the unseen coordinates: Xc_O Xc_O' = Xc Xc' - Xc_M Xc_M', Xc_O r_O = Xc r - Xc_M r_M.
  const auto m = static_cast<Eigen::Index>(unseen.size());
  Eigen::MatrixXd XcM(others, m);
  Eigen::VectorXd rM(m);
  for (Eigen::Index j = 0; j < m; ++j) {
    const Eigen::Index c = unseen[static_cast<std::size_t>(j)];
    double mu = 0.0;
    for (Eigen::Index a = 0; a < others; ++a) mu += X(idx[a], c);
    mu *= inv;
    for (Eigen::Index a = 0; a < others; ++a) XcM(a, j) = X(idx[a], c) - mu;
    rM[j] = X(n, c) - mu;
  }
  A.noalias() -= XcM * XcM.transpose();
  rhs.noalias() -= XcM * rM;
  A.diagonal().array() += static_cast<double>(others - 1) * noise_variance;
  post.w = A.ldlt().solve(rhs);
  return post;
}

// The fill of subject n's unseen coordinates: the posterior mean of the others' model.
Eigen::VectorXd FillFromOthers(const Eigen::MatrixXd& X, const Eigen::MatrixXd& G, const Eigen::VectorXd& g,
                               Eigen::Index n, const std::vector<Eigen::Index>& unseen, double noise_variance,
                               int max_others) {
  const Posterior post = PosteriorFromOthers(X, G, g, n, unseen, noise_variance, max_others);
  Eigen::VectorXd fill(static_cast<Eigen::Index>(unseen.size()));
  for (std::size_t j = 0; j < unseen.size(); ++j)
    fill[static_cast<Eigen::Index>(j)] = post.Mean(X, unseen[j]);
  return fill;
}

// The local correction (ImputationOptions::local_scale_mm): the residuals x - posterior mean at the seen
// vertices within three lengths of an unseen one (at most kMaxRim, the nearest), carried to the unseen
// vertices by Gaussian-process regression, k(p, q) = sd^2 exp(-|p - q|^2 / (2 l^2)) on the subject's
// vertex positions, plus the noise variance on the diagonal.
constexpr Eigen::Index kMaxRim = 1200;

void AddLocalCorrection(const Eigen::MatrixXd& X, const Eigen::MatrixXd& G, const Eigen::VectorXd& g,
                        Eigen::Index n, const std::vector<Eigen::Index>& unseen,
                        const Eigen::Matrix<bool, Eigen::Dynamic, Eigen::Dynamic>& seen,
                        const ImputationOptions& o, Eigen::VectorXd* fill) {
  const double l = o.local_scale_mm;
  const Eigen::Index m = seen.cols();
  auto position = [&](Eigen::Index v) { return Eigen::Vector3d(X.row(n).segment<3>(3 * v).transpose()); };
  std::vector<Eigen::Index> missing;
  for (Eigen::Index v = 0; v < m; ++v)
    if (!seen(n, v)) missing.push_back(v);
  std::vector<std::pair<double, Eigen::Index>> rim;  // (squared distance to the nearest unseen, vertex)
  for (Eigen::Index v = 0; v < m; ++v) {
    if (!seen(n, v)) continue;
    const Eigen::Vector3d p = position(v);
    double best = std::numeric_limits<double>::infinity();
    for (Eigen::Index u : missing) best = std::min(best, (position(u) - p).squaredNorm());
    if (best <= 9.0 * l * l) rim.emplace_back(best, v);
  }
  if (rim.empty()) return;
  if (static_cast<Eigen::Index>(rim.size()) > kMaxRim) {
    std::nth_element(rim.begin(), rim.begin() + kMaxRim, rim.end());
    rim.resize(static_cast<std::size_t>(kMaxRim));
  }
  std::vector<Eigen::Index> rim_coordinates;
  for (const auto& r : rim)
    rim_coordinates.insert(rim_coordinates.end(), {3 * r.second, 3 * r.second + 1, 3 * r.second + 2});
  const Posterior post = PosteriorFromOthers(X, G, g, n, unseen, o.noise_mm * o.noise_mm, o.max_others);
  const auto b = static_cast<Eigen::Index>(rim.size());
  Eigen::MatrixXd residual(b, 3);
  for (Eigen::Index i = 0; i < b; ++i)
    for (int d = 0; d < 3; ++d) {
      const Eigen::Index c = 3 * rim[static_cast<std::size_t>(i)].second + d;
      residual(i, d) = X(n, c) - post.Mean(X, c);
    }
  const double sd2 = o.local_sd_mm * o.local_sd_mm, inv2l2 = 1.0 / (2.0 * l * l);
  Eigen::MatrixXd K(b, b);
  for (Eigen::Index i = 0; i < b; ++i)
    for (Eigen::Index j = 0; j <= i; ++j)
      K(i, j) = K(j, i) = sd2 * std::exp(-(position(rim[static_cast<std::size_t>(i)].second) -
                                           position(rim[static_cast<std::size_t>(j)].second))
                                              .squaredNorm() *
                                         inv2l2);
  K.diagonal().array() += o.noise_mm * o.noise_mm;
  const Eigen::MatrixXd alpha = K.llt().solve(residual);
  for (std::size_t j = 0; j < missing.size(); ++j) {
    const Eigen::Vector3d p = position(missing[j]);
    Eigen::RowVector3d correction = Eigen::RowVector3d::Zero();
    for (Eigen::Index i = 0; i < b; ++i)
      correction +=
          sd2 * std::exp(-(position(rim[static_cast<std::size_t>(i)].second) - p).squaredNorm() * inv2l2) *
          alpha.row(i);
    // unseen lists the coordinates of the unseen vertices in vertex order, as `missing`.
    fill->segment<3>(3 * static_cast<Eigen::Index>(j)) += correction.transpose();
  }
}

// The core's Gram matrix X_S X_S' (K = S's rows), blocks of rows computed on the runner's processes;
// its lower triangle mirrored, so that it is symmetric to the bit.
Eigen::MatrixXd CoreGram(const Eigen::MatrixXd& X, Eigen::Index K, TaskRunner& runner) {
  using RowMajor = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
  const Eigen::Index kGramRows = BlockRows(K, 32);
  RowMajor table(K, K);
  runner.ComputeBlocks(
      BlockOffsets(K, kGramRows, K),
      [&](int b, double* out) {
        const Eigen::Index first = b * kGramRows, rows = std::min(kGramRows, K - first);
        Eigen::Map<RowMajor>(out, rows, K).noalias() = X.middleRows(first, rows) * X.topRows(K).transpose();
      },
      table.data());
  Eigen::MatrixXd G = table;
  G.triangularView<Eigen::StrictlyUpper>() = G.transpose();
  return G;
}

// Work on subjects `rows` in blocks (BlockRows: up to 8 subjects), one block per task: block b holds, for
// each of its subjects in turn, that subject's unseen coordinates (their new values); fill(n, g, out) writes
// subject n's, given g = X_S x_n if `with_g` (the block's columns of X_S X', one product for the block).
std::vector<Eigen::VectorXd> PerSubject(
    const Eigen::MatrixXd& X, Eigen::Index K, const std::vector<Eigen::Index>& rows,
    const std::vector<std::vector<Eigen::Index>>& unseen, bool with_g, TaskRunner& runner,
    const std::function<void(Eigen::Index, const Eigen::VectorXd&, double*)>& fill) {
  const auto kSubjects = static_cast<std::size_t>(BlockRows(static_cast<std::int64_t>(rows.size()), 8));
  std::vector<std::int64_t> offsets{0}, starts;
  for (std::size_t k = 0; k < rows.size(); ++k) {
    starts.push_back(k == 0 ? 0 : starts.back() + static_cast<std::int64_t>(unseen[rows[k - 1]].size()));
    if ((k + 1) % kSubjects == 0 || k + 1 == rows.size())
      offsets.push_back(starts.back() + static_cast<std::int64_t>(unseen[rows[k]].size()));
  }
  std::vector<double> table(static_cast<std::size_t>(offsets.back()));
  runner.ComputeBlocks(
      offsets,
      [&](int b, double* out) {
        const std::size_t first = static_cast<std::size_t>(b) * kSubjects;
        const std::size_t count = std::min(kSubjects, rows.size() - first);
        Eigen::MatrixXd g;
        if (with_g) {
          Eigen::MatrixXd block(static_cast<Eigen::Index>(count), X.cols());
          for (std::size_t j = 0; j < count; ++j)
            block.row(static_cast<Eigen::Index>(j)) = X.row(rows[first + j]);
          g = X.topRows(K) * block.transpose();
        }
        for (std::size_t j = 0; j < count; ++j) {
          fill(rows[first + j],
               with_g ? Eigen::VectorXd(g.col(static_cast<Eigen::Index>(j))) : Eigen::VectorXd(),
               out + (starts[first + j] - starts[first]));
        }
      },
      table.data());
  std::vector<Eigen::VectorXd> values(rows.size());
  for (std::size_t k = 0; k < rows.size(); ++k) {
    values[k] = Eigen::Map<const Eigen::VectorXd>(table.data() + starts[k],
                                                  static_cast<Eigen::Index>(unseen[rows[k]].size()));
  }
  return values;
}

}  // namespace

ImputationResult ImputeMissingVertices(const Eigen::MatrixXd& shapes,
                                       const Eigen::Matrix<bool, Eigen::Dynamic, Eigen::Dynamic>& seen,
                                       const ImputationOptions& options, const std::string& what,
                                       TaskRunner* runner) {
  std::string why;
  if (!options.IsValid(&why)) ThrowUsage(why);
  const Eigen::Index N = shapes.rows();
  if (N < 3) ThrowBadInput(what, "imputation needs at least 3 shapes, got " + std::to_string(N));
  if (shapes.cols() % 3 != 0 || seen.rows() != N || 3 * seen.cols() != shapes.cols()) {
    ThrowBadInput(what, std::to_string(N) + " shapes of " + std::to_string(shapes.cols()) +
                            " numbers do not match a seen-mask of " + std::to_string(seen.rows()) + " by " +
                            std::to_string(seen.cols()) + " vertices");
  }
  if (!shapes.allFinite()) ThrowBadInput(what, "a shape has a non-finite coordinate");

  ImputationResult result;
  result.shapes = shapes;
  result.filled_vertices.assign(static_cast<std::size_t>(N), 0);
  result.largest_change_mm.assign(static_cast<std::size_t>(N), 0.0);
  std::vector<std::vector<Eigen::Index>> unseen(static_cast<std::size_t>(N));
  std::vector<Eigen::Index> to_fill;
  for (Eigen::Index n = 0; n < N; ++n) {
    const Eigen::Index count = seen.cols() - seen.row(n).count();
    if (count == 0) continue;
    if (static_cast<double>(seen.row(n).count()) <
        options.min_seen_fraction * static_cast<double>(seen.cols())) {
      result.too_little_seen.push_back(static_cast<int>(n));
      continue;
    }
    unseen[static_cast<std::size_t>(n)] = UnseenCoordinates(seen, n);
    result.filled_vertices[static_cast<std::size_t>(n)] = static_cast<int>(count);
    to_fill.push_back(n);
  }

  // The core: the subjects every model of the others is made of (the first max_others + 1 rows; every row
  // of a cohort that small). Only their fills feed back into the others', so only they are iterated; each
  // subject beyond the core is filled once, from the core's converged fills (the same fixed point as
  // sweeping it too, at a fraction of the cost for a cohort of thousands: docs/cluster.md).
  const double noise_variance = options.noise_mm * options.noise_mm;
  const Eigen::Index core = std::min<Eigen::Index>(N, static_cast<Eigen::Index>(options.max_others) + 1);
  std::vector<Eigen::Index> core_fill, late_fill;
  for (Eigen::Index n : to_fill) (n < core ? core_fill : late_fill).push_back(n);
  SerialTaskRunner serial;
  TaskRunner& farm = runner != nullptr ? *runner : serial;
  Eigen::MatrixXd X = shapes;
  auto as_size = [](Eigen::Index n) { return static_cast<std::size_t>(n); };
  // Sets the new values of subjects `rows`; returns the largest move of a coordinate.
  // Moves subjects `rows` by `step` of the way to their new values; returns the largest distance to them.
  auto update = [&](const std::vector<Eigen::Index>& rows, const std::vector<Eigen::VectorXd>& values,
                    double step = 1.0) {
    double change = 0.0;
    for (std::size_t k = 0; k < rows.size(); ++k) {
      const std::vector<Eigen::Index>& c = unseen[as_size(rows[k])];
      for (std::size_t j = 0; j < c.size(); ++j) {
        const double v = values[k][static_cast<Eigen::Index>(j)];
        change = std::max(change, std::abs(v - X(rows[k], c[j])));
        X(rows[k], c[j]) += step * (v - X(rows[k], c[j]));
      }
    }
    return change;
  };
  // Each subject of `rows` filled from the others' current fills (Jacobi: all from the same X).
  auto fill_from_others = [&](const std::vector<Eigen::Index>& rows, const Eigen::MatrixXd& G) {
    const bool late = rows.front() >= core;  // all beyond the core, or all in it
    return PerSubject(
        X, core, rows, unseen, late, farm, [&](Eigen::Index n, const Eigen::VectorXd& g, double* out) {
          const Eigen::VectorXd f = FillFromOthers(X, G, n < core ? Eigen::VectorXd(G.col(n)) : g, n,
                                                   unseen[as_size(n)], noise_variance, options.max_others);
          std::copy(f.data(), f.data() + f.size(), out);
        });
  };
  // The sweeps move every fill at once (Jacobi), which overshoots where the subjects' fills lean on each
  // other strongly (large holes in a small cohort: 60 subjects with 60 % holed diverged to 386 mm): a sweep
  // whose fills would move farther than the last one's halves the step (under-relaxation), down to 1/64.
  // Convergence is judged on the full distance to the new fills, not on the damped move.
  double step = 1.0, previous = std::numeric_limits<double>::infinity();
  for (int it = 0; it < options.max_iterations && !core_fill.empty(); ++it) {
    result.iterations = it + 1;
    const std::vector<Eigen::VectorXd> fills = fill_from_others(core_fill, CoreGram(X, core, farm));
    double distance = 0.0;
    for (std::size_t k = 0; k < core_fill.size(); ++k) {
      const std::vector<Eigen::Index>& c = unseen[as_size(core_fill[k])];
      for (std::size_t j = 0; j < c.size(); ++j)
        distance =
            std::max(distance, std::abs(fills[k][static_cast<Eigen::Index>(j)] - X(core_fill[k], c[j])));
    }
    if (distance > previous) step = std::max(step / 2.0, 1.0 / 64.0);
    previous = distance;
    result.last_change_mm = update(core_fill, fills, step);
    if (result.last_change_mm <= options.tolerance_mm) {
      result.converged = true;
      break;
    }
  }
  if (core_fill.empty()) result.converged = true;
  if (!late_fill.empty() || (options.local_scale_mm > 0.0 && !to_fill.empty())) {
    const Eigen::MatrixXd G = CoreGram(X, core, farm);  // of the converged core
    if (!late_fill.empty()) update(late_fill, fill_from_others(late_fill, G));
    if (options.local_scale_mm > 0.0 && !to_fill.empty()) {
      // The local correction of every fill, once the fills have converged.
      update(to_fill, PerSubject(X, core, to_fill, unseen, true, farm,
                                 [&](Eigen::Index n, const Eigen::VectorXd& g, double* out) {
                                   const std::vector<Eigen::Index>& c = unseen[as_size(n)];
                                   Eigen::VectorXd fill(static_cast<Eigen::Index>(c.size()));
                                   for (std::size_t j = 0; j < c.size(); ++j)
                                     fill[static_cast<Eigen::Index>(j)] = X(n, c[j]);
                                   AddLocalCorrection(X, G, g, n, c, seen, options, &fill);
                                   std::copy(fill.data(), fill.data() + fill.size(), out);
                                 }));
    }
  }
  for (Eigen::Index n : to_fill) {
    double largest = 0.0;
    for (Eigen::Index v = 0; v < seen.cols(); ++v) {
      if (!seen(n, v))
        largest = std::max(largest, (X.row(n).segment<3>(3 * v) - shapes.row(n).segment<3>(3 * v)).norm());
    }
    result.largest_change_mm[static_cast<std::size_t>(n)] = largest;
  }
  result.shapes = std::move(X);

  int vertices = 0;
  for (int c : result.filled_vertices) vertices += c;
  std::ostringstream msg;
  msg << vertices << " unseen vertices of " << to_fill.size() << " of " << N
      << " subjects filled from the others";
  if (!to_fill.empty()) {
    msg << " in " << result.iterations << " iterations ("
        << (result.converged ? "converged" : "not converged") << ", last change " << result.last_change_mm
        << " mm)";
  }
  if (!result.too_little_seen.empty()) {
    msg << "; " << result.too_little_seen.size() << " seen too little, left as resampled";
  }
  result.message = msg.str();
  return result;
}

}  // namespace pectus
