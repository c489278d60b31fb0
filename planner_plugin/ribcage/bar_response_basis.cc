#include "planner_plugin/ribcage/bar_response_basis.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <functional>
#include <numbers>

#include "planner_plugin/fem/surface_load.h"
#include "shape/core/error.h"

namespace pectus::planner {

bool BarResponseBasisOptions::IsValid(std::string* why) const {
  if (!(tolerance_mm > 0.0) || !std::isfinite(tolerance_mm) || !(max_force_n > 0.0) ||
      !std::isfinite(max_force_n)) {
    if (why) *why = "the basis' tolerance (mm) and largest force (N) must be > 0";
    return false;
  }
  if (samples_per_width < 1) {
    if (why) *why = "the basis needs at least 1 bar level per contact width";
    return false;
  }
  if (block_columns < 1) {
    if (why) *why = "the basis needs at least 1 right-hand side per block";
    return false;
  }
  return true;
}

namespace {

// out[i] = sum_j U(i, j) c[j] over the panels (BarResponseBasis::panels_): single-precision modes, double
// sums, kPanel coordinates at a time. Compiled also for AVX2 and chosen at load time where the processor
// has it (GCC's function multi-versioning); the build itself targets plain x86-64.
#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__)
__attribute__((target_clones("avx2", "default")))
#endif
void PanelsTimesVector(const float* panels, const double* c, Eigen::Index begin, Eigen::Index end, Eigen::Index r,
                       double* out) noexcept {
  constexpr int P = 8;
  for (Eigen::Index first = begin - begin % P; first < end; first += P) {
    const float* panel = panels + first * r;
    double sum[P] = {};
    for (Eigen::Index j = 0; j < r; ++j) {
      for (int k = 0; k < P; ++k) sum[k] += static_cast<double>(panel[j * P + k]) * c[j];
    }
    for (Eigen::Index k = std::max<Eigen::Index>(0, begin - first); k < P && first + k < end; ++k)
      out[first + k] = sum[k];
  }
}

double Since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

BarResponseBasis::BarResponseBasis(const RibcageFem& fem, const std::vector<NodeTies>& points,
                                   const BarResponseBasisOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) ThrowUsage("bar response basis: " + why);
  const PatientRibcage& ribcage = fem.ribcage();
  const Points3& x = ribcage.mesh.nodes;
  const Eigen::Index n = x.rows();
  for (std::size_t p = 0; p < points.size(); ++p) {
    for (const auto& [node, w] : points[p]) {
      if (node < 0 || node >= n || !std::isfinite(w)) {
        ThrowUsage("bar response basis: output point " + std::to_string(p) + " is tied to node " +
                   std::to_string(node) + " (the mesh has " + std::to_string(n) +
                   ") or has a non-finite weight");
      }
    }
  }
  num_points_ = static_cast<Eigen::Index>(points.size());
  contact_width_mm_ = fem.options().contact_width_mm;
  notch_z_mm_ = ribcage.measured.notch_z_mm;
  sternal_length_mm_ = ribcage.measured.sternal_length_mm;

  // The contact nodes and the quadrature of the profile over the sternum's back (AddProfiledTraction's).
  const Tri6Connectivity& faces = ribcage.sternum_posterior_faces;
  std::vector<std::int32_t> index_of(static_cast<std::size_t>(n), -1);
  for (Eigen::Index f = 0; f < faces.rows(); ++f) {
    for (int a = 0; a < 6; ++a) {
      const std::int32_t node = faces(f, a);
      if (index_of[static_cast<std::size_t>(node)] < 0) {
        index_of[static_cast<std::size_t>(node)] = static_cast<std::int32_t>(contact_nodes_.size());
        contact_nodes_.push_back(node);
      }
    }
  }
  for (const FaceQuadraturePoint& fq : FaceQuadrature7(x, faces)) {
    QuadraturePoint q;
    q.z = fq.x.z();
    q.weight = fq.weight;
    for (int a = 0; a < 6; ++a) {
      q.contact[a] = index_of[static_cast<std::size_t>(fq.nodes[a])];
      q.N[a] = fq.N[a];
    }
    quadrature_.push_back(q);
  }
  std::sort(quadrature_.begin(), quadrature_.end(),
            [](const QuadraturePoint& a, const QuadraturePoint& b) { return a.z < b.z; });

  // Solves blocks of right-hand sides (3 #nodes each) on the one factorisation; `use` gets each block.
  const auto J = static_cast<Eigen::Index>(contact_nodes_.size());
  const Eigen::Vector3d d = fem.options().push_direction.normalized();
  auto solve = [&](Eigen::Index columns, const std::function<void(Eigen::Index, Eigen::VectorXd*)>& load,
                   const std::function<void(Eigen::Index, const Points3&)>& use) {
    for (Eigen::Index first = 0; first < columns; first += options.block_columns) {
      const Eigen::Index count = std::min<Eigen::Index>(options.block_columns, columns - first);
      std::vector<LoadCase> cases(static_cast<std::size_t>(count));
      for (Eigen::Index c = 0; c < count; ++c) {
        cases[static_cast<std::size_t>(c)].name = "basis column " + std::to_string(first + c);
        cases[static_cast<std::size_t>(c)].nodal_forces = Eigen::VectorXd::Zero(3 * n);
        load(first + c, &cases[static_cast<std::size_t>(c)].nodal_forces);
      }
      const std::vector<Points3> u = fem.solver().Solve(cases);
      for (Eigen::Index c = 0; c < count; ++c) use(first + c, u[static_cast<std::size_t>(c)]);
    }
  };

  // 1. The responses Y (3P x S) of the output points to the bar at levels every
  // `samples_per_width`-th of the contact width, covering every level where the profile touches the
  // sternum (the loads F = d (x) W, W: J x S the contact weights at those levels). A unit push at one
  // node is a point load with a sharp, local response, but a bar's weights w(s) are smooth in s, so these
  // responses span what any bar does.
  auto start = std::chrono::steady_clock::now();
  const double step = contact_width_mm_ / options.samples_per_width;
  const double lowest = quadrature_.front().z - contact_width_mm_,
               highest = quadrature_.back().z + contact_width_mm_;
  std::vector<Eigen::VectorXd> samples;
  {
    BarResponseWorkspace ws;
    ws.weights = Eigen::VectorXd::Zero(J);
    ws.mark.assign(static_cast<std::size_t>(J), 0);
    ws.touched.reserve(static_cast<std::size_t>(J));
    for (double z = lowest; z <= highest; z += step) {
      if (Weights(z, &ws)) samples.push_back(ws.weights);
    }
  }
  const auto S = static_cast<Eigen::Index>(samples.size());
  Eigen::MatrixXd Y(3 * num_points_, S);
  solve(
      S,
      [&](Eigen::Index k, Eigen::VectorXd* f) {
        for (Eigen::Index j = 0; j < J; ++j)
          f->segment<3>(3 * contact_nodes_[static_cast<std::size_t>(j)]) =
              samples[static_cast<std::size_t>(k)][j] * d;
      },
      [&](Eigen::Index k, const Points3& u) {
        for (Eigen::Index p = 0; p < num_points_; ++p) {
          Eigen::RowVector3d v = Eigen::RowVector3d::Zero();
          for (const auto& [node, w] : points[static_cast<std::size_t>(p)]) v += w * u.row(node);
          Y.block<3, 1>(3 * p, k) = v.transpose();
        }
      });
  timings_s_.Add("solve_bar_levels", Since(start));

  // 2. The modes: the left singular vectors U_r of Y (through the S x S Gram matrix Y'Y = V S^2 V'), the
  // fewest for which the error at the sampled levels (2-norm over every output coordinate) is at most
  // sigma_{r+1} per newton <= tolerance / largest force.
  start = std::chrono::steady_clock::now();
  Eigen::MatrixXd gram(S, S);
  gram.setZero();
  gram.selfadjointView<Eigen::Lower>().rankUpdate(Y.transpose());
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(gram.selfadjointView<Eigen::Lower>());
  singular_values_ = eig.eigenvalues().reverse().cwiseMax(0.0).cwiseSqrt();  // descending
  const Eigen::VectorXd& sv = singular_values_;
  const double cut = options.tolerance_mm / options.max_force_n;
  Eigen::Index r = 0;
  while (r < sv.size() && sv[r] > cut) ++r;
  const Eigen::MatrixXd V = eig.eigenvectors().rowwise().reverse().leftCols(r);
  const Eigen::MatrixXd modes = Y * V * sv.head(r).cwiseInverse().asDiagonal();  // U_r, orthonormal columns
  timings_s_.Add("compress", Since(start));

  // 3. The mixing M = U_r' P K^-1 D (r x J; P the output ties, D the unit pushes d e_j) by the adjoint:
  // K is symmetric, so M[:, j] = d . Z[node_j] with Z = K^-1 P' U_r, r right-hand sides (and one more,
  // K^-1 l for the lift functional l, for the exact lift per unit push), instead of J.
  start = std::chrono::steady_clock::now();
  Eigen::MatrixXd mixing(r, J);
  lift_.resize(J);
  const std::vector<std::pair<std::int32_t, double>> lift_ties = fem.SternumLiftTies();
  solve(
      r + 1,
      [&](Eigen::Index k, Eigen::VectorXd* f) {
        if (k == r) {
          for (const auto& [node, w] : lift_ties) (*f)[3 * node + 1] += w;  // the lift reads -u_y (ties' w)
          return;
        }
        for (Eigen::Index p = 0; p < num_points_; ++p) {
          for (const auto& [node, w] : points[static_cast<std::size_t>(p)])
            f->segment<3>(3 * node) += w * modes.block<3, 1>(3 * p, k);
        }
      },
      [&](Eigen::Index k, const Points3& z) {
        for (Eigen::Index j = 0; j < J; ++j) {
          const double v = z.row(contact_nodes_[static_cast<std::size_t>(j)]).dot(d.transpose());
          if (k == r) {
            lift_[j] = v;
          } else {
            mixing(k, j) = v;
          }
        }
      });
  timings_s_.Add("solve_adjoint", Since(start));
  start = std::chrono::steady_clock::now();

  mixing_ = std::move(mixing);
  Pack(modes);
  truncation_bound_mm_per_n_ = r < sv.size() ? sv[r] : 0.0;
  timings_s_.Add("pack", Since(start));
}

template <typename Modes>
void BarResponseBasis::Pack(const Modes& modes) {
  static_assert(kPanel == 8, "PanelsTimesVector sums 8 coordinates at a time");
  rows_ = modes.rows();
  rank_ = modes.cols();
  const Eigen::Index r = rank_;
  const Eigen::MatrixXd& mixing = mixing_;
  const Eigen::Index panels = (rows_ + kPanel - 1) / kPanel;
  panels_.assign(static_cast<std::size_t>(panels * kPanel * r), 0.0f);
  for (Eigen::Index i = 0; i < rows_; ++i) {
    for (Eigen::Index j = 0; j < r; ++j) {
      panels_[static_cast<std::size_t>((i / kPanel) * kPanel * r + j * kPanel + i % kPanel)] =
          static_cast<float>(modes(i, j));
    }
  }

  // 3. Evaluation in O(r) after two binary searches. With the profile phi_q = (1 + cos(pi (z_q - s) / W)) / 2
  // = (1 + cos(pi z_q / W) cos(pi s / W) + sin(pi z_q / W) sin(pi s / W)) / 2, every window sum over the
  // quadrature points with |z_q - s| < W is three differences of prefix sums: of the point's weight
  // (for the area), of its share of the mixing m_q = w_q sum_a N_a M[:, j_a] (for the coefficients) and
  // of its share of the exact lift (for the force to lift), each plain, times cos and times sin.
  const auto Q = static_cast<Eigen::Index>(quadrature_.size());
  z_.resize(Q);
  for (int k = 0; k < 3; ++k) {
    prefix_area_[k] = Eigen::VectorXd::Zero(Q + 1);
    prefix_lift_[k] = Eigen::VectorXd::Zero(Q + 1);
    prefix_mixing_[k] = Eigen::MatrixXd::Zero(r, Q + 1);
  }
  Eigen::VectorXd m(r);
  for (Eigen::Index q = 0; q < Q; ++q) {
    const QuadraturePoint& p = quadrature_[static_cast<std::size_t>(q)];
    z_[q] = p.z;
    m.setZero();
    double lift = 0.0;
    for (int a = 0; a < 6; ++a) {
      m += p.N[a] * mixing.col(p.contact[a]);
      lift += p.N[a] * lift_[p.contact[a]];
    }
    const double angle = std::numbers::pi * p.z / contact_width_mm_;
    const double factor[3] = {1.0, std::cos(angle), std::sin(angle)};
    for (int k = 0; k < 3; ++k) {
      prefix_area_[k][q + 1] = prefix_area_[k][q] + p.weight * factor[k];
      prefix_lift_[k][q + 1] = prefix_lift_[k][q] + p.weight * lift * factor[k];
      prefix_mixing_[k].col(q + 1) = prefix_mixing_[k].col(q) + (p.weight * factor[k]) * m;
    }
  }
}

BarResponseWorkspace BarResponseBasis::MakeWorkspace() const {
  BarResponseWorkspace ws;
  ws.weights = Eigen::VectorXd::Zero(num_contact_nodes());
  ws.coefficients = Eigen::VectorXd::Zero(rank());
  ws.touched.reserve(contact_nodes_.size());
  ws.mark.assign(contact_nodes_.size(), 0);
  return ws;
}

bool BarResponseBasis::Window(double level_z_mm, Eigen::Index* first, Eigen::Index* last, double* c,
                              double* s) const noexcept {
  const double* begin = z_.data();
  const double* end = begin + z_.size();
  *first = std::lower_bound(begin, end, level_z_mm - contact_width_mm_) - begin;
  *last = std::lower_bound(begin, end, level_z_mm + contact_width_mm_) - begin;
  const double angle = std::numbers::pi * level_z_mm / contact_width_mm_;
  *c = std::cos(angle);
  *s = std::sin(angle);
  return *last > *first;
}

double BarResponseBasis::WindowSum(const Eigen::VectorXd (&prefix)[3], Eigen::Index first, Eigen::Index last,
                                   double c, double s) noexcept {
  return 0.5 * ((prefix[0][last] - prefix[0][first]) + c * (prefix[1][last] - prefix[1][first]) +
                s * (prefix[2][last] - prefix[2][first]));
}

bool BarResponseBasis::Weights(double level_z_mm, BarResponseWorkspace* ws) const noexcept {
  for (std::int32_t j : ws->touched) ws->weights[j] = 0.0, ws->mark[static_cast<std::size_t>(j)] = 0;
  ws->touched.clear();
  const double width = contact_width_mm_;
  auto it = std::lower_bound(quadrature_.begin(), quadrature_.end(), level_z_mm - width,
                             [](const QuadraturePoint& q, double z) { return q.z < z; });
  double total = 0.0;
  for (; it != quadrature_.end() && it->z < level_z_mm + width; ++it) {
    // RibcageFem::ContactProfile: a raised cosine of full width `width` at half maximum.
    const double t = std::abs(it->z - level_z_mm) / width;
    const double w = it->weight * 0.5 * (1.0 + std::cos(std::numbers::pi * t));
    if (w == 0.0) continue;
    total += w;
    for (int a = 0; a < 6; ++a) {
      const std::int32_t j = it->contact[a];
      if (!ws->mark[static_cast<std::size_t>(j)]) {
        ws->mark[static_cast<std::size_t>(j)] = 1;
        ws->touched.push_back(j);  // capacity reserved for every contact node: no allocation
      }
      ws->weights[j] += w * it->N[a];
    }
  }
  if (!(total > 0.0)) return false;
  for (std::int32_t j : ws->touched) ws->weights[j] /= total;
  return true;
}

bool BarResponseBasis::CoefficientsPerNewton(double level_z_mm, BarResponseWorkspace* ws) const noexcept {
  Eigen::Index first = 0, last = 0;
  double c = 0.0, s = 0.0;
  if (!Window(level_z_mm, &first, &last, &c, &s)) return false;
  const double area = WindowSum(prefix_area_, first, last, c, s);
  if (!(area > kLeastArea * prefix_area_[0][z_.size()])) return false;
  const double scale = 0.5 / area;
  ws->coefficients.noalias() = scale * ((prefix_mixing_[0].col(last) - prefix_mixing_[0].col(first)) +
                                        c * (prefix_mixing_[1].col(last) - prefix_mixing_[1].col(first)) +
                                        s * (prefix_mixing_[2].col(last) - prefix_mixing_[2].col(first)));
  return true;
}

bool BarResponseBasis::Evaluate(double level_z_mm, double force_n, BarResponseWorkspace* ws, double* out,
                                Eigen::Index first_row, Eigen::Index end_row) const noexcept {
  if (!CoefficientsPerNewton(level_z_mm, ws)) return false;
  ws->coefficients *= force_n;
  const Eigen::Index begin = std::clamp<Eigen::Index>(first_row, 0, rows_);
  const Eigen::Index end = end_row < 0 ? rows_ : std::clamp<Eigen::Index>(end_row, begin, rows_);
  PanelsTimesVector(panels_.data(), ws->coefficients.data(), begin, end, rank_, out);
  return true;
}

void BarResponseBasis::CopyModes(float* out) const noexcept {
  for (Eigen::Index i = 0; i < rows_; ++i) {
    for (Eigen::Index j = 0; j < rank_; ++j) out[i * rank_ + j] = Mode(i, j);
  }
}

double BarResponseBasis::LiftPerNewton(double level_z_mm) const noexcept {
  Eigen::Index first = 0, last = 0;
  double c = 0.0, s = 0.0;
  if (!Window(level_z_mm, &first, &last, &c, &s)) return 0.0;
  const double area = WindowSum(prefix_area_, first, last, c, s);
  if (!(area > kLeastArea * prefix_area_[0][z_.size()])) return 0.0;
  return WindowSum(prefix_lift_, first, last, c, s) / area;
}

std::size_t BarResponseBasis::bytes() const {
  std::size_t numbers =
      panels_.size() / 2 + static_cast<std::size_t>(lift_.size() + z_.size() + mixing_.size());
  for (int k = 0; k < 3; ++k)
    numbers +=
        static_cast<std::size_t>(prefix_area_[k].size() + prefix_lift_[k].size() + prefix_mixing_[k].size());
  return sizeof(double) * numbers + sizeof(QuadraturePoint) * quadrature_.size() +
         sizeof(std::int32_t) * contact_nodes_.size();
}

BarResponseBasis::Stored BarResponseBasis::ToStored() const {
  Stored out;
  out.num_points = num_points_;
  out.contact_width_mm = contact_width_mm_;
  out.notch_z_mm = notch_z_mm_;
  out.sternal_length_mm = sternal_length_mm_;
  out.truncation_bound_mm_per_n = truncation_bound_mm_per_n_;
  out.contact_nodes = contact_nodes_;
  const auto Q = static_cast<Eigen::Index>(quadrature_.size());
  out.quadrature_z.resize(Q);
  out.quadrature_weight.resize(Q);
  out.quadrature_contact.resize(Q, 6);
  out.quadrature_N.resize(Q, 6);
  for (Eigen::Index q = 0; q < Q; ++q) {
    const QuadraturePoint& p = quadrature_[static_cast<std::size_t>(q)];
    out.quadrature_z[q] = p.z;
    out.quadrature_weight[q] = p.weight;
    for (int a = 0; a < 6; ++a) {
      out.quadrature_contact(q, a) = p.contact[a];
      out.quadrature_N(q, a) = p.N[a];
    }
  }
  out.modes.resize(rows_, rank_);
  for (Eigen::Index i = 0; i < rows_; ++i) {
    for (Eigen::Index j = 0; j < rank_; ++j) out.modes(i, j) = Mode(i, j);
  }
  out.mixing = mixing_;
  out.lift = lift_;
  out.singular_values = singular_values_;
  return out;
}

BarResponseBasis::BarResponseBasis(Stored stored, const std::string& source) {
  auto bad = [&source](const std::string& what) { ThrowBadInput(source, "response basis: " + what); };
  const auto J = static_cast<Eigen::Index>(stored.contact_nodes.size());
  const Eigen::Index Q = stored.quadrature_z.size(), r = stored.modes.cols();
  if (stored.num_points <= 0 || stored.modes.rows() != 3 * stored.num_points)
    bad("the modes have " + std::to_string(stored.modes.rows()) + " rows for " +
        std::to_string(stored.num_points) + " points (3 per point)");
  if (J == 0 || Q == 0) bad("no contact nodes or no quadrature points");
  if (stored.quadrature_weight.size() != Q || stored.quadrature_contact.rows() != Q ||
      stored.quadrature_contact.cols() != 6 || stored.quadrature_N.rows() != Q ||
      stored.quadrature_N.cols() != 6)
    bad("the quadrature's arrays differ in length (or are not 6 per point)");
  if (stored.mixing.rows() != r || stored.mixing.cols() != J || stored.lift.size() != J)
    bad("the mixing is not rank by #contact nodes, or the lift not one per contact node");
  if (!(stored.contact_width_mm > 0 && std::isfinite(stored.contact_width_mm)) ||
      !std::isfinite(stored.notch_z_mm) ||
      !(stored.sternal_length_mm > 0 && std::isfinite(stored.sternal_length_mm)) ||
      !(stored.truncation_bound_mm_per_n >= 0 && std::isfinite(stored.truncation_bound_mm_per_n)))
    bad("the contact width, sternal length and truncation bound must be positive and finite");
  if (!stored.modes.allFinite() || !stored.mixing.allFinite() || !stored.lift.allFinite() ||
      !stored.quadrature_z.allFinite() || !stored.quadrature_weight.allFinite() ||
      !stored.quadrature_N.allFinite() || !stored.singular_values.allFinite())
    bad("holds a non-finite number");
  if ((stored.quadrature_weight.array() < 0).any()) bad("a quadrature weight is negative");
  for (Eigen::Index q = 0; q + 1 < Q; ++q) {
    if (stored.quadrature_z[q + 1] < stored.quadrature_z[q])
      bad("the quadrature points are not in ascending z");
  }
  if ((stored.quadrature_contact.array() < 0).any() || (stored.quadrature_contact.array() >= J).any())
    bad("a quadrature point refers to a contact node beyond the " + std::to_string(J));
  for (std::int32_t node : stored.contact_nodes) {
    if (node < 0) bad("a contact node has a negative index");
  }
  num_points_ = stored.num_points;
  contact_width_mm_ = stored.contact_width_mm;
  notch_z_mm_ = stored.notch_z_mm;
  sternal_length_mm_ = stored.sternal_length_mm;
  truncation_bound_mm_per_n_ = stored.truncation_bound_mm_per_n;
  contact_nodes_ = std::move(stored.contact_nodes);
  quadrature_.resize(static_cast<std::size_t>(Q));
  for (Eigen::Index q = 0; q < Q; ++q) {
    QuadraturePoint& p = quadrature_[static_cast<std::size_t>(q)];
    p.z = stored.quadrature_z[q];
    p.weight = stored.quadrature_weight[q];
    for (int a = 0; a < 6; ++a) {
      p.contact[a] = stored.quadrature_contact(q, a);
      p.N[a] = stored.quadrature_N(q, a);
    }
  }
  mixing_ = std::move(stored.mixing);
  lift_ = std::move(stored.lift);
  singular_values_ = std::move(stored.singular_values);
  const auto start = std::chrono::steady_clock::now();
  Pack(stored.modes);
  timings_s_.Add("pack", Since(start));
}

}  // namespace pectus::planner
