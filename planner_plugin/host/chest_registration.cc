#include "planner_plugin/host/chest_registration.h"

#include <Eigen/Geometry>
#include <cmath>

#include "shape/core/error.h"

namespace pectus::planner {
namespace {

// Columns: sternal axis (notch to xiphoid), lateral, anterior (right-handed).
Eigen::Matrix3d ChestFrame(const LandmarkSet& set, const Eigen::Vector3d& anterior, const std::string& what) {
  const Eigen::Vector3d axis = set.Position("xiphoid", what) - set.Position("sternal_notch", what);
  if (axis.norm() < 1.0) ThrowBadInput(what, "the sternal notch and the xiphoid coincide");
  const Eigen::Vector3d e1 = axis.normalized();
  const Eigen::Vector3d a = anterior - anterior.dot(e1) * e1;
  if (a.norm() < 0.1 * anterior.norm() || !(anterior.norm() > 0)) {
    ThrowBadInput(what, "the anterior direction is (nearly) parallel to the sternal axis");
  }
  const Eigen::Vector3d e3 = a.normalized();
  Eigen::Matrix3d frame;
  frame << e1, e3.cross(e1), e3;
  return frame;
}

}  // namespace

bool ChestRegistrationOptions::IsValid(std::string* why) const {
  bool notch = false, xiphoid = false;
  for (const std::string& label : labels) {
    notch = notch || label == "sternal_notch";
    xiphoid = xiphoid || label == "xiphoid";
  }
  if (!notch || !xiphoid) {
    if (why) *why = "the registration needs the landmarks sternal_notch and xiphoid";
    return false;
  }
  return true;
}

Eigen::Vector3d AnteriorDirection(const TriangleMesh& mesh, const std::string& what) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  const Points3& x = mesh.vertices.positions;
  for (Eigen::Index f = 0; f < mesh.num_faces(); ++f) {
    const Eigen::Vector3d a = x.row(mesh.faces(f, 0)).transpose();
    sum += (x.row(mesh.faces(f, 1)).transpose() - a).cross(x.row(mesh.faces(f, 2)).transpose() - a);
  }
  if (!(sum.norm() > 0)) ThrowBadInput(what, "the surface has no area, so it has no anterior direction");
  return sum.normalized();
}

ChestRegistrationResult RegisterChestByLandmarks(const LandmarkSet& source,
                                                 const Eigen::Vector3d& source_anterior,
                                                 const LandmarkSet& target,
                                                 const Eigen::Vector3d& target_anterior,
                                                 const ChestRegistrationOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) ThrowUsage("chest registration: " + why);
  const Eigen::Matrix3d R = ChestFrame(target, target_anterior, "average chest landmarks") *
                            ChestFrame(source, source_anterior, "predicted chest landmarks").transpose();
  ChestRegistrationResult out;
  std::vector<Eigen::Vector3d> p, q;
  for (const std::string& label : options.labels) {
    const Landmark* a = source.Find(label);
    const Landmark* b = target.Find(label);
    if (a == nullptr || b == nullptr) continue;
    out.used.push_back(label);
    p.push_back(a->position);
    q.push_back(b->position);
  }
  Eigen::Vector3d p_mean = Eigen::Vector3d::Zero(), q_mean = Eigen::Vector3d::Zero();
  for (std::size_t i = 0; i < p.size(); ++i) {
    p_mean += p[i] / static_cast<double>(p.size());
    q_mean += q[i] / static_cast<double>(q.size());
  }
  // Least squares of sum |s R p_i + t - q_i|^2 with R fixed: s from the centred points, t from the means.
  double cross = 0, norm = 0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    cross += (R * (p[i] - p_mean)).dot(q[i] - q_mean);
    norm += (p[i] - p_mean).squaredNorm();
  }
  const double s = options.similarity ? cross / norm : 1.0;
  if (!(s > 0) || !std::isfinite(s))
    ThrowBadInput("predicted chest landmarks", "the landmarks give no valid scale");
  out.T_target_source.scale = s;
  out.T_target_source.rotation = R;
  out.T_target_source.translation = q_mean - s * (R * p_mean);
  double sum = 0;
  for (std::size_t i = 0; i < p.size(); ++i) sum += (out.T_target_source * p[i] - q[i]).squaredNorm();
  out.landmark_rms_mm = std::sqrt(sum / static_cast<double>(p.size()));
  return out;
}

}  // namespace pectus::planner
