// pectus planner: consistent nodal forces of tractions on 6-node boundary triangles.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <functional>
#include <vector>

#include "planner_plugin/fem/tet_mesh.h"
#include "shape/core/geometry.h"

namespace pectus::planner {

/// Total area of the 6-node triangles `faces` (mm²), integrated with their quadratic geometry.
/// @param[in] nodes  #nodes by 3 positions, mm
double FacesArea(const Points3& nodes, const Tri6Connectivity& faces);

/// Adds to `forces` the consistent nodal forces f_a = integral N_a t dA of a uniform traction t over
/// `faces` (3-point rule per face, exact for flat faces).
/// @param[in]     nodes     #nodes by 3 positions, mm
/// @param[in]     faces     6-node boundary triangles
/// @param[in]     traction  traction vector, N/mm² (MPa)
/// @param[in,out] forces    3 #nodes nodal forces (x, y, z per node), N
void AddUniformTraction(const Points3& nodes, const Tri6Connectivity& faces, const Eigen::Vector3d& traction,
                        Eigen::VectorXd* forces);

/// Spreads a total force over a contact patch as a uniform traction F / area (so the nodal forces sum
/// to F exactly). Throws Error(kBadInput) if the patch is empty or has zero area.
void AddForceOverPatch(const Points3& nodes, const Tri6Connectivity& patch, const Eigen::Vector3d& force_n,
                       Eigen::VectorXd* forces);

/// One point of the 7-point rule (Dunavant, degree 5) on a 6-node boundary triangle: where it lies, its
/// weight (the rule's weight times the area element, mm²) and the face's nodes with their shape
/// functions there. A traction t phi(x) gives node nodes[a] the force sum over points of
/// weight phi(x) N[a] t.
struct FaceQuadraturePoint {
  Eigen::Vector3d x;
  double weight = 0.0;
  std::array<std::int32_t, 6> nodes{};
  std::array<double, 6> N{};
};

/// The 7-point rule of AddProfiledTraction over `faces`, 7 points per face in face order.
/// @param[in] nodes  #nodes by 3 positions, mm
std::vector<FaceQuadraturePoint> FaceQuadrature7(const Points3& nodes, const Tri6Connectivity& faces);

/// Adds to `forces` the consistent nodal forces f_a = integral N_a phi(x) t dA of a traction t shaped by
/// a profile phi >= 0 (7-point rule per face, degree 5), and returns integral phi dA (mm²). A profile
/// that moves continuously moves the forces continuously (unlike a patch of whole faces).
/// @param[in]     nodes    #nodes by 3 positions, mm
/// @param[in]     faces    6-node boundary triangles
/// @param[in]     traction traction vector at phi = 1, N/mm²
/// @param[in]     phi      the profile, a function of position (mm)
/// @param[in,out] forces   3 #nodes nodal forces, N (nullptr: only the integral)
double AddProfiledTraction(const Points3& nodes, const Tri6Connectivity& faces,
                           const Eigen::Vector3d& traction,
                           const std::function<double(const Eigen::Vector3d&)>& phi, Eigen::VectorXd* forces);

}  // namespace pectus::planner
