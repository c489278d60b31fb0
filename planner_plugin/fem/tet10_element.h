// pectus planner: the 10-node (quadratic) tetrahedron, isoparametric, for linear elasticity.
#pragma once

#include <Eigen/Core>

#include "planner_plugin/fem/material.h"

namespace pectus::planner {

/// 10 by 3 node positions of one element (mm), in the TetMesh node order.
using Tet10Nodes = Eigen::Matrix<double, 10, 3>;
/// 30 by 30 element stiffness, N/mm; degrees of freedom ordered (u_x, u_y, u_z) node by node.
using Tet10Stiffness = Eigen::Matrix<double, 30, 30>;

/// The 10 quadratic shape functions at reference coordinates (xi, eta, zeta), with barycentric
/// coordinates L0 = 1 - xi - eta - zeta, L1 = xi, L2 = eta, L3 = zeta:
/// corners N_i = L_i (2 L_i - 1), mid-edge N_{4+e} = 4 L_i L_j for edge e = (i, j) of kTet10Edges.
Eigen::Matrix<double, 10, 1> Tet10ShapeFunctions(const Eigen::Vector3d& xi);

/// 10 by 3 derivatives dN_a / d(xi, eta, zeta) at reference coordinates `xi`.
Eigen::Matrix<double, 10, 3> Tet10ShapeDerivatives(const Eigen::Vector3d& xi);

/// The 4-point Gauss rule on the reference tetrahedron (degree 2: exact for the stiffness of a
/// straight-edged 10-node tetrahedron, whose strains are linear): points and weights (sum 1/6).
const Eigen::Matrix<double, 4, 3>& Tet10GaussPoints();
const Eigen::Vector4d& Tet10GaussWeights();

/// 6 by 30 strain-displacement matrix B (engineering shear strains, Voigt order of material.h) at
/// reference coordinates `xi`, and the Jacobian determinant there (mm³ per reference volume).
/// @return false if the Jacobian determinant is not positive (an inverted or flat element).
bool Tet10StrainDisplacement(const Tet10Nodes& X, const Eigen::Vector3d& xi, Eigen::Matrix<double, 6, 30>* B,
                             double* det_jacobian);

/// Element stiffness K_e = sum_g w_g B_g^T D B_g det J_g over the 4-point rule.
/// @param[in]  X  node positions, mm
/// @param[in]  D  elasticity matrix, MPa
/// @param[out] K  stiffness, N/mm
/// @return false if the element is inverted or flat at a Gauss point (K is then undefined).
bool Tet10ElementStiffness(const Tet10Nodes& X, const ElasticityMatrix& D, Tet10Stiffness* K);

}  // namespace pectus::planner
