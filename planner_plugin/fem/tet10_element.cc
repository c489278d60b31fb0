#include "planner_plugin/fem/tet10_element.h"

#include <Eigen/LU>

#include "planner_plugin/fem/tet_mesh.h"

namespace pectus::planner {

Eigen::Matrix<double, 10, 1> Tet10ShapeFunctions(const Eigen::Vector3d& xi) {
  const double L[4] = {1.0 - xi(0) - xi(1) - xi(2), xi(0), xi(1), xi(2)};
  Eigen::Matrix<double, 10, 1> N;
  for (int i = 0; i < 4; ++i) N(i) = L[i] * (2.0 * L[i] - 1.0);
  for (int e = 0; e < 6; ++e) N(4 + e) = 4.0 * L[kTet10Edges[e][0]] * L[kTet10Edges[e][1]];
  return N;
}

Eigen::Matrix<double, 10, 3> Tet10ShapeDerivatives(const Eigen::Vector3d& xi) {
  const double L[4] = {1.0 - xi(0) - xi(1) - xi(2), xi(0), xi(1), xi(2)};
  // dL_i / d(xi, eta, zeta): L0 -> (-1, -1, -1), L1 -> e1, L2 -> e2, L3 -> e3.
  Eigen::Matrix<double, 4, 3> dL;
  dL << -1, -1, -1, 1, 0, 0, 0, 1, 0, 0, 0, 1;
  Eigen::Matrix<double, 10, 3> dN;
  for (int i = 0; i < 4; ++i) dN.row(i) = (4.0 * L[i] - 1.0) * dL.row(i);
  for (int e = 0; e < 6; ++e) {
    const int i = kTet10Edges[e][0], j = kTet10Edges[e][1];
    dN.row(4 + e) = 4.0 * (L[j] * dL.row(i) + L[i] * dL.row(j));
  }
  return dN;
}

const Eigen::Matrix<double, 4, 3>& Tet10GaussPoints() {
  static const Eigen::Matrix<double, 4, 3> points = [] {
    const double a = 0.5854101966249685, b = 0.1381966011250105;  // (5 + 3 sqrt 5) / 20, (5 - sqrt 5) / 20
    Eigen::Matrix<double, 4, 3> p;
    p << b, b, b, a, b, b, b, a, b, b, b, a;
    return p;
  }();
  return points;
}

const Eigen::Vector4d& Tet10GaussWeights() {
  static const Eigen::Vector4d weights = Eigen::Vector4d::Constant(1.0 / 24.0);
  return weights;
}

bool Tet10StrainDisplacement(const Tet10Nodes& X, const Eigen::Vector3d& xi, Eigen::Matrix<double, 6, 30>* B,
                             double* det_jacobian) {
  const Eigen::Matrix<double, 10, 3> dN_dxi = Tet10ShapeDerivatives(xi);
  const Eigen::Matrix3d J = X.transpose() * dN_dxi;  // J(i, k) = d x_i / d xi_k
  const double det = J.determinant();
  *det_jacobian = det;
  if (!(det > 0.0)) return false;
  const Eigen::Matrix<double, 10, 3> dN = dN_dxi * J.inverse();  // dN_a / dx
  B->setZero();
  for (int a = 0; a < 10; ++a) {
    const double dx = dN(a, 0), dy = dN(a, 1), dz = dN(a, 2);
    const int c = 3 * a;
    (*B)(0, c + 0) = dx;
    (*B)(1, c + 1) = dy;
    (*B)(2, c + 2) = dz;
    (*B)(3, c + 0) = dy;
    (*B)(3, c + 1) = dx;
    (*B)(4, c + 1) = dz;
    (*B)(4, c + 2) = dy;
    (*B)(5, c + 0) = dz;
    (*B)(5, c + 2) = dx;
  }
  return true;
}

bool Tet10ElementStiffness(const Tet10Nodes& X, const ElasticityMatrix& D, Tet10Stiffness* K) {
  K->setZero();
  Eigen::Matrix<double, 6, 30> B;
  for (int g = 0; g < 4; ++g) {
    double det = 0.0;
    if (!Tet10StrainDisplacement(X, Tet10GaussPoints().row(g).transpose(), &B, &det)) return false;
    const Eigen::Matrix<double, 6, 30> DB = D * B;
    K->noalias() += (Tet10GaussWeights()(g) * det) * (B.transpose() * DB);
  }
  return true;
}

}  // namespace pectus::planner
