#include "planner_plugin/fem/surface_load.h"

#include "shape/core/error.h"

namespace pectus::planner {
namespace {

// 3-point rule on the reference triangle (degree 2), area 1/2.
constexpr double kPoints[3][2] = {{1.0 / 6.0, 1.0 / 6.0}, {2.0 / 3.0, 1.0 / 6.0}, {1.0 / 6.0, 2.0 / 3.0}};
constexpr double kWeight = 1.0 / 6.0;

// T6 shape functions and derivatives at (r, s); corners 0-2, mids (0,1), (1,2), (2,0).
void Tri6(double r, double s, Eigen::Matrix<double, 6, 1>* N, Eigen::Matrix<double, 6, 2>* dN) {
  const double l0 = 1.0 - r - s, l1 = r, l2 = s;
  *N << l0 * (2 * l0 - 1), l1 * (2 * l1 - 1), l2 * (2 * l2 - 1), 4 * l0 * l1, 4 * l1 * l2, 4 * l2 * l0;
  // d/dr and d/ds with dl0 = (-1, -1), dl1 = (1, 0), dl2 = (0, 1).
  *dN << -(4 * l0 - 1), -(4 * l0 - 1), (4 * l1 - 1), 0, 0, (4 * l2 - 1), 4 * (l0 - l1), -4 * l1, 4 * l2,
      4 * l1, -4 * l2, 4 * (l0 - l2);
}

// Integrates N_a dA over one face: the 6 weights w_a with f_a = w_a t.
Eigen::Matrix<double, 6, 1> FaceWeights(const Points3& nodes, const Eigen::Matrix<std::int32_t, 1, 6>& face) {
  Eigen::Matrix<double, 6, 3> X;
  for (int a = 0; a < 6; ++a) X.row(a) = nodes.row(face(a));
  Eigen::Matrix<double, 6, 1> w = Eigen::Matrix<double, 6, 1>::Zero();
  Eigen::Matrix<double, 6, 1> N;
  Eigen::Matrix<double, 6, 2> dN;
  for (const auto& p : kPoints) {
    Tri6(p[0], p[1], &N, &dN);
    const Eigen::Vector3d xr = X.transpose() * dN.col(0), xs = X.transpose() * dN.col(1);
    w += (kWeight * xr.cross(xs).norm()) * N;
  }
  return w;
}

// Dunavant's 7-point rule on the reference triangle (degree 5): (r, s) and weights summing to 1/2.
constexpr double kA1 = 0.059715871789770, kB1 = 0.470142064105115;
constexpr double kA2 = 0.797426985353087, kB2 = 0.101286507323456;
constexpr double kPoints7[7][2] = {
    {1.0 / 3.0, 1.0 / 3.0}, {kB1, kB1}, {kA1, kB1}, {kB1, kA1}, {kB2, kB2}, {kA2, kB2}, {kB2, kA2}};
constexpr double kWeights7[7] = {0.5 * 0.225,
                                 0.5 * 0.132394152788506,
                                 0.5 * 0.132394152788506,
                                 0.5 * 0.132394152788506,
                                 0.5 * 0.125939180544827,
                                 0.5 * 0.125939180544827,
                                 0.5 * 0.125939180544827};

}  // namespace

std::vector<FaceQuadraturePoint> FaceQuadrature7(const Points3& nodes, const Tri6Connectivity& faces) {
  std::vector<FaceQuadraturePoint> points;
  points.reserve(static_cast<std::size_t>(7 * faces.rows()));
  Eigen::Matrix<double, 6, 1> N;
  Eigen::Matrix<double, 6, 2> dN;
  for (Eigen::Index f = 0; f < faces.rows(); ++f) {
    Eigen::Matrix<double, 6, 3> X;
    for (int a = 0; a < 6; ++a) X.row(a) = nodes.row(faces(f, a));
    for (int q = 0; q < 7; ++q) {
      Tri6(kPoints7[q][0], kPoints7[q][1], &N, &dN);
      const Eigen::Vector3d xr = X.transpose() * dN.col(0), xs = X.transpose() * dN.col(1);
      FaceQuadraturePoint& p = points.emplace_back();
      p.x = X.transpose() * N;
      p.weight = kWeights7[q] * xr.cross(xs).norm();
      for (int a = 0; a < 6; ++a) p.nodes[a] = faces(f, a), p.N[a] = N(a);
    }
  }
  return points;
}

double AddProfiledTraction(const Points3& nodes, const Tri6Connectivity& faces,
                           const Eigen::Vector3d& traction,
                           const std::function<double(const Eigen::Vector3d&)>& phi,
                           Eigen::VectorXd* forces) {
  double integral = 0.0;
  for (const FaceQuadraturePoint& p : FaceQuadrature7(nodes, faces)) {
    const double w = p.weight * phi(p.x);
    if (w == 0.0) continue;
    integral += w;
    if (forces == nullptr) continue;
    for (int a = 0; a < 6; ++a) forces->segment<3>(3 * p.nodes[a]) += (w * p.N[a]) * traction;
  }
  return integral;
}

double FacesArea(const Points3& nodes, const Tri6Connectivity& faces) {
  double area = 0.0;
  for (Eigen::Index f = 0; f < faces.rows(); ++f) area += FaceWeights(nodes, faces.row(f)).sum();
  return area;
}

void AddUniformTraction(const Points3& nodes, const Tri6Connectivity& faces, const Eigen::Vector3d& traction,
                        Eigen::VectorXd* forces) {
  for (Eigen::Index f = 0; f < faces.rows(); ++f) {
    const Eigen::Matrix<double, 6, 1> w = FaceWeights(nodes, faces.row(f));
    for (int a = 0; a < 6; ++a) forces->segment<3>(3 * faces(f, a)) += w(a) * traction;
  }
}

void AddForceOverPatch(const Points3& nodes, const Tri6Connectivity& patch, const Eigen::Vector3d& force_n,
                       Eigen::VectorXd* forces) {
  const double area = FacesArea(nodes, patch);
  if (patch.rows() == 0 || !(area > 0.0)) {
    ThrowBadInput("contact patch",
                  "the patch has no faces or zero area, so the force cannot be spread over it");
  }
  AddUniformTraction(nodes, patch, force_n / area, forces);
}

}  // namespace pectus::planner
