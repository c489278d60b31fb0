#include "planner_plugin/ribcage/bar_response_basis.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <chrono>
#include <cmath>
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
  if (block_columns < 1) {
    if (why) *why = "the basis needs at least 1 right-hand side per block";
    return false;
  }
  return true;
}

namespace {

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

  // 1. The response to a unit push at every contact node, kept at the output points (R, 3P x J) and at
  // the sternal lift, block by block of right-hand sides on the one factorisation.
  auto start = std::chrono::steady_clock::now();
  const auto J = static_cast<Eigen::Index>(contact_nodes_.size());
  Eigen::MatrixXd R(3 * num_points_, J);
  lift_.resize(J);
  const Eigen::Vector3d d = fem.options().push_direction.normalized();
  for (Eigen::Index first = 0; first < J; first += options.block_columns) {
    const Eigen::Index count = std::min<Eigen::Index>(options.block_columns, J - first);
    std::vector<LoadCase> cases(static_cast<std::size_t>(count));
    for (Eigen::Index c = 0; c < count; ++c) {
      LoadCase& load = cases[static_cast<std::size_t>(c)];
      load.name = "unit push at node " + std::to_string(contact_nodes_[static_cast<std::size_t>(first + c)]);
      load.nodal_forces = Eigen::VectorXd::Zero(3 * n);
      load.nodal_forces.segment<3>(3 * contact_nodes_[static_cast<std::size_t>(first + c)]) = d;
    }
    const std::vector<Points3> u = fem.solver().Solve(cases);
    for (Eigen::Index c = 0; c < count; ++c) {
      const Points3& uc = u[static_cast<std::size_t>(c)];
      lift_[first + c] = fem.SternumLift(uc);
      for (Eigen::Index p = 0; p < num_points_; ++p) {
        Eigen::RowVector3d v = Eigen::RowVector3d::Zero();
        for (const auto& [node, w] : points[static_cast<std::size_t>(p)]) v += w * uc.row(node);
        R.block<3, 1>(3 * p, first + c) = v.transpose();
      }
    }
  }
  timings_s_.Add("solve", Since(start));

  // 2. Compression in the space of the loads a bar can make. A unit push at one node is a point load with
  // a sharp, local response (R has full rank J), but a bar's weights w(s) are smooth in its level s, so
  // the responses Y = R W to the bar at levels every kSamplesPerWidth-th of the contact width (W: J x S,
  // covering every level where the profile touches the sternum) span what any bar does. Their left
  // singular vectors U_r (through the S x S Gram matrix Y'Y = V S^2 V') give the modes U_r and the
  // mixing M = U_r' R, so that u(s) = U_r M w(s); at the sampled levels the error (2-norm over every
  // output coordinate) is at most sigma_{r+1} per newton.
  start = std::chrono::steady_clock::now();
  constexpr int kSamplesPerWidth = 16;
  const double step = contact_width_mm_ / kSamplesPerWidth;
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
  Eigen::MatrixXd W(J, static_cast<Eigen::Index>(samples.size()));
  for (std::size_t k = 0; k < samples.size(); ++k) W.col(static_cast<Eigen::Index>(k)) = samples[k];
  const Eigen::MatrixXd Y = R * W;
  Eigen::MatrixXd gram(Y.cols(), Y.cols());
  gram.setZero();
  gram.selfadjointView<Eigen::Lower>().rankUpdate(Y.transpose());
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(gram.selfadjointView<Eigen::Lower>());
  singular_values_ = eig.eigenvalues().reverse().cwiseMax(0.0).cwiseSqrt();  // descending
  const Eigen::VectorXd& sv = singular_values_;
  const double cut = options.tolerance_mm / options.max_force_n;
  Eigen::Index r = 0;
  while (r < sv.size() && sv[r] > cut) ++r;
  const Eigen::MatrixXd V = eig.eigenvectors().rowwise().reverse().leftCols(r);
  modes_ = Y * V * sv.head(r).cwiseInverse().asDiagonal();  // U_r, orthonormal columns
  mixing_ = modes_.transpose() * R;
  truncation_bound_mm_per_n_ = r < sv.size() ? sv[r] : 0.0;
  timings_s_.Add("compress", Since(start));
}

BarResponseWorkspace BarResponseBasis::MakeWorkspace() const {
  BarResponseWorkspace ws;
  ws.weights = Eigen::VectorXd::Zero(num_contact_nodes());
  ws.coefficients = Eigen::VectorXd::Zero(rank());
  ws.touched.reserve(contact_nodes_.size());
  ws.mark.assign(contact_nodes_.size(), 0);
  return ws;
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

bool BarResponseBasis::Evaluate(double level_z_mm, double force_n, BarResponseWorkspace* ws,
                                double* out) const noexcept {
  if (!Weights(level_z_mm, ws)) return false;
  ws->coefficients.setZero();
  for (std::int32_t j : ws->touched)
    ws->coefficients.noalias() += (force_n * ws->weights[j]) * mixing_.col(j);
  Eigen::Map<Eigen::VectorXd>(out, modes_.rows()).noalias() = modes_ * ws->coefficients;
  return true;
}

double BarResponseBasis::LiftPerNewton(double level_z_mm, BarResponseWorkspace* ws) const noexcept {
  if (!Weights(level_z_mm, ws)) return 0.0;
  double lift = 0.0;
  for (std::int32_t j : ws->touched) lift += ws->weights[j] * lift_[j];
  return lift;
}

std::size_t BarResponseBasis::bytes() const {
  return sizeof(double) * static_cast<std::size_t>(modes_.size() + mixing_.size() + lift_.size()) +
         sizeof(QuadraturePoint) * quadrature_.size() + sizeof(std::int32_t) * contact_nodes_.size();
}

}  // namespace pectus::planner
