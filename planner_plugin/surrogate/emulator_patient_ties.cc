#include "planner_plugin/surrogate/emulator_patient_ties.h"

#include "planner_plugin/ribcage/ribcage_fem.h"
#include "shape/core/error.h"

namespace pectus::planner {

EmulatorPatientTies MakeEmulatorPatientTies(const PatientRibcage& ribcage, const SkinSurface& skin,
                                            const std::vector<std::int32_t>& boundary_nodes) {
  std::vector<std::int32_t> index(static_cast<std::size_t>(ribcage.mesh.num_nodes()), -1);
  for (std::size_t b = 0; b < boundary_nodes.size(); ++b) {
    const std::int32_t node = boundary_nodes[b];
    if (node < 0 || node >= ribcage.mesh.num_nodes())
      ThrowUsage("emulator ties: patient " + ribcage.patient + ": boundary node " + std::to_string(node) +
                 " is not a node of the mesh");
    index[static_cast<std::size_t>(node)] = static_cast<std::int32_t>(b);
  }
  auto boundary_index = [&](std::int32_t node, const char* what) {
    const std::int32_t b = index[static_cast<std::size_t>(node)];
    if (b < 0)
      ThrowFailure("emulator ties: patient " + ribcage.patient + ": " + what + " is tied to node " +
                   std::to_string(node) + ", not a boundary node");
    return b;
  };
  const auto nb = static_cast<Eigen::Index>(boundary_nodes.size());
  EmulatorPatientTies out;
  std::vector<Eigen::Triplet<double>> entries;
  for (std::size_t j = 0; j < skin.ties.size(); ++j)
    for (const auto& [node, w] : skin.ties[j])
      entries.emplace_back(static_cast<int>(j), boundary_index(node, "a skin vertex"), w);
  out.skin.resize(static_cast<Eigen::Index>(skin.ties.size()), nb);
  out.skin.setFromTriplets(entries.begin(), entries.end());
  entries.clear();
  // The lift reads the anterior (-y) displacement: the y coordinate of each tied node.
  for (const auto& [node, w] : SternumLiftTiesOf(ribcage))
    entries.emplace_back(0, 3 * boundary_index(node, "the sternal lift") + 1, w);
  out.lift.resize(1, 3 * nb);
  out.lift.setFromTriplets(entries.begin(), entries.end());
  return out;
}

ResponseEmulatorPrediction ThroughTies(const ResponseEmulatorPrediction& nodes,
                                       const EmulatorPatientTies& ties) {
  using Rows3 = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;
  const Eigen::Index nb = ties.skin.cols();
  ResponseEmulatorPrediction out;
  const auto q = static_cast<Eigen::Index>(nodes.response.size());
  out.lift_per_newton.resize(q);
  out.lift_sd.resize(q);
  const Eigen::SparseMatrix<double, Eigen::RowMajor> abs_skin = ties.skin.cwiseAbs(),
                                                     abs_lift = ties.lift.cwiseAbs();
  auto carry = [&](const Eigen::SparseMatrix<double, Eigen::RowMajor>& t,
                   const Eigen::VectorXd& v) -> Eigen::VectorXd {
    const Rows3 r = t * Eigen::Map<const Rows3>(v.data(), nb, 3);
    return Eigen::Map<const Eigen::VectorXd>(r.data(), r.size());
  };
  for (Eigen::Index k = 0; k < q; ++k) {
    const Eigen::VectorXd& u = nodes.response[static_cast<std::size_t>(k)];
    const Eigen::VectorXd& sd = nodes.response_sd[static_cast<std::size_t>(k)];
    if (u.size() != 3 * nb || sd.size() != 3 * nb || ties.lift.cols() != 3 * nb)
      ThrowUsage("emulator ties: a prediction of " + std::to_string(u.size()) + " coordinates for ties to " +
                 std::to_string(nb) + " boundary nodes");
    out.response.push_back(carry(ties.skin, u));
    out.response_sd.push_back(carry(abs_skin, sd));
    out.lift_per_newton(k) = (ties.lift * u)(0);
    out.lift_sd(k) = (abs_lift * sd)(0);
  }
  return out;
}

}  // namespace pectus::planner
