#include "shape/surface/local_rbf.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/QR>
#include <cmath>

namespace pectus {
namespace {

inline double Cube(double r) { return r * r * r; }

// Monomials of degree <= 2 at a point of the local frame: 1, x, y, z, x^2, y^2, z^2, xy, xz, yz.
inline void Monomials(const double* x, int terms, double* out) {
  out[0] = 1.0;
  out[1] = x[0];
  out[2] = x[1];
  out[3] = x[2];
  if (terms == 4) return;
  out[4] = x[0] * x[0];
  out[5] = x[1] * x[1];
  out[6] = x[2] * x[2];
  out[7] = x[0] * x[1];
  out[8] = x[0] * x[2];
  out[9] = x[1] * x[2];
}

// Rows of monomials (#points by terms) of the rows of a #points by 3 matrix.
Eigen::MatrixXd MonomialMatrix(const Points3& x, int terms) {
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> p(x.rows(), terms);
  for (Eigen::Index i = 0; i < x.rows(); ++i) Monomials(x.row(i).data(), terms, p.row(i).data());
  return p;
}

}  // namespace

bool LocalRbf::Fit(const LocalRbfProblem& problem, double smoothing) {
  const Eigen::Index m = problem.centres.rows();
  const Eigen::Index n = problem.points.rows();
  if (n < 4 || problem.values.size() != n || problem.weights.size() != n || !(problem.scale > 0.0) ||
      !(smoothing >= 0.0)) {
    return false;
  }
  const double inv_scale = 1.0 / problem.scale;
  const Eigen::RowVector3d o = problem.origin.transpose();
  const Points3 y = (problem.centres.rowwise() - o) * inv_scale;
  const Points3 x = (problem.points.rowwise() - o) * inv_scale;
  const double weight_sum = problem.weights.sum();
  if (!(weight_sum > 0.0)) return false;
  const Eigen::VectorXd w = problem.weights / weight_sum;
  const Eigen::VectorXd f = problem.values * inv_scale;

  // P_x (n by terms) and the weighted polynomial block: the constraints must fix the polynomial. A
  // quadratic that they cannot fix falls back to a linear one.
  int terms = problem.quadratic ? 10 : 4;
  Eigen::MatrixXd px;
  for (;; terms = 4) {
    px = MonomialMatrix(x, terms);
    const Eigen::MatrixXd ptp = px.transpose() * w.asDiagonal() * px;
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> ptp_eig(ptp, Eigen::EigenvaluesOnly);
    if (ptp_eig.eigenvalues()(0) > 1e-10 * ptp_eig.eigenvalues()(terms - 1)) break;
    if (terms == 4) return false;
  }

  // Null space Z of the side conditions P_y^T alpha = 0 (dissertation Eq. 10, second block row).
  Eigen::MatrixXd z(m, 0);
  if (m > 0) {
    const Eigen::MatrixXd py = MonomialMatrix(y, terms);
    Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(py);
    qr.setThreshold(1e-9);
    const Eigen::Index rank = qr.rank();
    if (m > rank) {
      const Eigen::MatrixXd q = qr.householderQ();
      z = q.rightCols(m - rank);
    }
  }
  const Eigen::Index g = z.cols();

  // Kernel matrices Phi(x, y) (n by m) and Phi(y, y) (m by m).
  Eigen::MatrixXd kxy(n, m);
  for (Eigen::Index j = 0; j < m; ++j) {
    for (Eigen::Index k = 0; k < n; ++k) kxy(k, j) = Cube((x.row(k) - y.row(j)).norm());
  }
  Eigen::MatrixXd kyy(m, m);
  for (Eigen::Index j = 0; j < m; ++j) {
    kyy(j, j) = 0.0;
    for (Eigen::Index i = j + 1; i < m; ++i) kyy(i, j) = kyy(j, i) = Cube((y.row(i) - y.row(j)).norm());
  }

  // Design D = [Phi(x, y) Z, P_x]; normal equations (D^T W D + smoothing * blockdiag(Z^T Phi Z, 0)) u =
  // D^T W f, built on the lower triangle only.
  Eigen::MatrixXd d(n, g + terms);
  d.leftCols(g).noalias() = kxy * z;
  d.rightCols(terms) = px;
  const Eigen::MatrixXd dw = w.cwiseSqrt().asDiagonal() * d;
  Eigen::MatrixXd normal = Eigen::MatrixXd::Zero(g + terms, g + terms);
  normal.selfadjointView<Eigen::Lower>().rankUpdate(dw.transpose());
  if (g > 0 && smoothing > 0.0) {
    const Eigen::MatrixXd kz = kyy * z;
    normal.topLeftCorner(g, g).triangularView<Eigen::Lower>() += smoothing * (z.transpose() * kz);
  }
  const double ridge = 1e-12 * (normal.trace() / double(g + terms) + 1e-300);
  normal.diagonal().array() += ridge;
  const Eigen::VectorXd rhs = d.transpose() * (w.asDiagonal() * f);
  const Eigen::LDLT<Eigen::MatrixXd> ldlt(normal);
  if (ldlt.info() != Eigen::Success) return false;
  const Eigen::VectorXd u = ldlt.solve(rhs);
  if (!u.allFinite()) return false;

  centres_ = y;
  alpha_ = z * u.head(g);
  beta_.setZero();
  beta_.head(terms) = u.tail(terms);
  terms_ = terms;
  origin_ = problem.origin;
  scale_ = problem.scale;
  return true;
}

double LocalRbf::Evaluate(const Eigen::Vector3d& x) const {
  const Eigen::Vector3d xl = (x - origin_) / scale_;
  double mono[10];
  Monomials(xl.data(), terms_, mono);
  double s = 0.0;
  for (int t = 0; t < terms_; ++t) s += beta_(t) * mono[t];
  // One column per axis, so that the kernels are summed two or four at a time (SIMD).
  const Eigen::Index m = centres_.rows();
  const double *cx = centres_.col(0).data(), *cy = centres_.col(1).data(), *cz = centres_.col(2).data();
  const double* a = alpha_.data();
  const double px = xl.x(), py = xl.y(), pz = xl.z();
  double k = 0.0;
#pragma omp simd reduction(+ : k)
  for (Eigen::Index j = 0; j < m; ++j) {
    const double dx = px - cx[j], dy = py - cy[j], dz = pz - cz[j];
    const double r2 = dx * dx + dy * dy + dz * dz;
    k += a[j] * r2 * std::sqrt(r2);
  }
  s += k;
  return s * scale_;
}

}  // namespace pectus
