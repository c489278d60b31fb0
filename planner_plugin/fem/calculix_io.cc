#include "planner_plugin/fem/calculix_io.h"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "shape/core/atomic_file.h"
#include "shape/core/error.h"

namespace pectus::planner {

void WriteCalculixInput(const std::filesystem::path& path, const TetMesh& mesh,
                        const std::vector<IsotropicMaterial>& materials,
                        const std::vector<std::int32_t>& prescribed_dofs, const LoadCase& load) {
  AtomicOutput out(path);
  std::ostream& s = out.stream();
  // CalculiX reads fields of at most 20 characters: 13 significant digits fit.
  char buf[256];
  s << "** pectus planner: static linear elasticity, C3D10, mm N MPa\n*NODE, NSET=NALL\n";
  for (Eigen::Index i = 0; i < mesh.num_nodes(); ++i) {
    std::snprintf(buf, sizeof(buf), "%lld, %.12E, %.12E, %.12E\n", static_cast<long long>(i + 1),
                  mesh.nodes(i, 0), mesh.nodes(i, 1), mesh.nodes(i, 2));
    s << buf;
  }
  for (std::size_t r = 0; r < materials.size(); ++r) {
    bool any = false;
    for (Eigen::Index t = 0; t < mesh.num_tets(); ++t) {
      if (mesh.regions(t) != static_cast<int>(r)) continue;
      if (!any) s << "*ELEMENT, TYPE=C3D10, ELSET=REGION" << r << "\n";
      any = true;
      s << (t + 1);
      for (int k = 0; k < 10; ++k) s << ", " << (mesh.tets(t, k) + 1);
      s << "\n";
    }
    if (!any) continue;
    std::snprintf(buf, sizeof(buf), "*MATERIAL, NAME=MAT%zu\n*ELASTIC\n%.12E, %.12E\n", r,
                  materials[r].youngs_modulus_mpa, materials[r].poisson_ratio);
    s << buf << "*SOLID SECTION, ELSET=REGION" << r << ", MATERIAL=MAT" << r << "\n";
  }
  s << "*STEP\n*STATIC\n";
  if (!prescribed_dofs.empty()) s << "*BOUNDARY\n";
  for (std::size_t k = 0; k < prescribed_dofs.size(); ++k) {
    const double value =
        load.prescribed_values.size() == 0 ? 0.0 : load.prescribed_values(static_cast<Eigen::Index>(k));
    const int node = prescribed_dofs[k] / 3 + 1, dof = prescribed_dofs[k] % 3 + 1;
    std::snprintf(buf, sizeof(buf), "%d, %d, %d, %.12E\n", node, dof, dof, value);
    s << buf;
  }
  bool header = false;
  for (Eigen::Index d = 0; d < load.nodal_forces.size(); ++d) {
    if (load.nodal_forces(d) == 0.0) continue;
    if (!header) s << "*CLOAD\n";
    header = true;
    std::snprintf(buf, sizeof(buf), "%lld, %lld, %.12E\n", static_cast<long long>(d / 3 + 1),
                  static_cast<long long>(d % 3 + 1), load.nodal_forces(d));
    s << buf;
  }
  s << "*NODE PRINT, NSET=NALL\nU\n*END STEP\n";
  out.Commit();
}

Points3 ReadCalculixDisplacements(const std::filesystem::path& path, Eigen::Index num_nodes) {
  std::ifstream in(path);
  if (!in) ThrowBadInput(path.string(), "cannot open the CalculiX results file");
  std::string line;
  std::int64_t line_number = 0;
  bool found = false;
  while (std::getline(in, line)) {
    ++line_number;
    if (line.find("displacements") != std::string::npos) {
      found = true;
      break;
    }
  }
  if (!found) ThrowBadInput(path.string(), "no 'displacements' block (was *NODE PRINT U requested?)");
  Points3 u = Points3::Constant(num_nodes, 3, std::numeric_limits<double>::quiet_NaN());
  std::vector<std::int64_t> listed_on(static_cast<std::size_t>(num_nodes), 0);  // line of each node's row
  Eigen::Index read = 0;
  while (std::getline(in, line)) {
    ++line_number;
    if (line.find_first_not_of(" \t\r") == std::string::npos) {
      if (read > 0) break;  // blank line after the block
      continue;
    }
    std::istringstream fields(line);
    long long node = 0;
    double x = 0, y = 0, z = 0;
    if (!(fields >> node >> x >> y >> z)) {
      if (read > 0) break;  // the next block's header
      ThrowBadInput(path.string(), "expected 'node ux uy uz'", line_number);
    }
    if (node < 1 || node > num_nodes) {
      ThrowBadInput(path.string(),
                    "node " + std::to_string(node) + " outside 1.." + std::to_string(num_nodes), line_number);
    }
    std::int64_t& first = listed_on[static_cast<std::size_t>(node - 1)];
    if (first > 0) {
      ThrowBadInput(
          path.string(),
          "node " + std::to_string(node) + " listed twice (first on line " + std::to_string(first) + ")",
          line_number);
    }
    if (!std::isfinite(x) || !std::isfinite(y) || !std::isfinite(z)) {
      ThrowBadInput(path.string(), "node " + std::to_string(node) + " has a non-finite displacement",
                    line_number);
    }
    first = line_number;
    u.row(node - 1) << x, y, z;
    ++read;
  }
  if (read != num_nodes) {
    ThrowBadInput(path.string(), "displacements of " + std::to_string(read) + " nodes, expected " +
                                     std::to_string(num_nodes));
  }
  return u;
}

}  // namespace pectus::planner
