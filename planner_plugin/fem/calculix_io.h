// pectus planner: export to and import from CalculiX (ccx), the independent solver the engine is
// verified against. An adaptor: nothing else in the engine depends on it.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <filesystem>
#include <vector>

#include "planner_plugin/fem/linear_elastic_solver.h"
#include "planner_plugin/fem/material.h"
#include "planner_plugin/fem/tet_mesh.h"
#include "shape/core/geometry.h"

namespace pectus::planner {

/// Writes a CalculiX/Abaqus input deck for one static load case: nodes (1-based), C3D10 elements in one
/// ELSET per region with its material and solid section, the prescribed dofs with their values
/// (*BOUNDARY), the nonzero nodal forces (*CLOAD), and *NODE PRINT of U for every node (to the .dat file).
/// Written atomically.
/// @param[in] path             output .inp
/// @param[in] mesh             quadratic mesh (node order of TetMesh = C3D10 order)
/// @param[in] materials        one per region
/// @param[in] prescribed_dofs  ascending global dofs (3 node + component)
/// @param[in] load             nodal forces (N) and prescribed values (mm, empty = zero)
void WriteCalculixInput(const std::filesystem::path& path, const TetMesh& mesh,
                        const std::vector<IsotropicMaterial>& materials,
                        const std::vector<std::int32_t>& prescribed_dofs, const LoadCase& load);

/// Reads the nodal displacements printed by *NODE PRINT U from a CalculiX .dat file.
/// @param[in] path       the .dat file
/// @param[in] num_nodes  number of nodes of the mesh
/// @return #num_nodes by 3 displacements, mm. Throws Error(kBadInput) naming the file (and line) if the
///         displacement block is missing, malformed or does not list every node.
Points3 ReadCalculixDisplacements(const std::filesystem::path& path, Eigen::Index num_nodes);

}  // namespace pectus::planner
