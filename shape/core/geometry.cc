#include "shape/core/geometry.h"

#include <cmath>
#include <string>

#include "shape/core/error.h"

namespace pectus {

void PointCloud::Validate(const std::string& what) const {
  const Eigen::Index n = size();
  if (has_normals() && normals.rows() != n) {
    ThrowBadInput(what, std::to_string(normals.rows()) + " normals for " + std::to_string(n) + " points");
  }
  if (has_colors() && colors.rows() != n) {
    ThrowBadInput(what, std::to_string(colors.rows()) + " colours for " + std::to_string(n) + " points");
  }
  for (const auto& [name, values] : scalars) {
    if (values.size() != n) {
      ThrowBadInput(what, "scalar '" + name + "' has " + std::to_string(values.size()) + " values for " +
                              std::to_string(n) + " points");
    }
  }
  for (Eigen::Index i = 0; i < n; ++i) {
    if (!positions.row(i).allFinite()) {
      ThrowBadInput(what, "point " + std::to_string(i) + " has a non-finite coordinate (NaN or Inf)");
    }
  }
}

void PointCloud::Resize(Eigen::Index n) {
  positions.conservativeResize(n, 3);
  if (has_normals()) normals.conservativeResize(n, 3);
  if (has_colors()) colors.conservativeResize(n, 3);
  for (auto& [name, values] : scalars) values.conservativeResize(n);
}

void PointCloud::Append(const PointCloud& other) {
  const Eigen::Index n0 = size(), n1 = other.size();
  const bool keep_normals = (n0 == 0 || has_normals()) && other.has_normals();
  const bool keep_colors = (n0 == 0 || has_colors()) && other.has_colors();
  Points3 p(n0 + n1, 3);
  p << positions, other.positions;
  positions.swap(p);
  if (keep_normals) {
    Points3 q(n0 + n1, 3);
    q << normals, other.normals;
    normals.swap(q);
  } else {
    normals.resize(0, 3);
  }
  if (keep_colors) {
    Colors3 c(n0 + n1, 3);
    c << colors, other.colors;
    colors.swap(c);
  } else {
    colors.resize(0, 3);
  }
  for (auto it = scalars.begin(); it != scalars.end();) {
    auto found = other.scalars.find(it->first);
    if (found == other.scalars.end() && n0 > 0) {
      it = scalars.erase(it);
      continue;
    }
    Eigen::VectorXd v(n0 + n1);
    v << it->second, found->second;
    it->second.swap(v);
    ++it;
  }
  if (n0 == 0) {
    for (const auto& [name, values] : other.scalars) scalars.emplace(name, values);
  }
}

void TriangleMesh::Validate(const std::string& what) const {
  vertices.Validate(what);
  const Eigen::Index n = vertices.size();
  for (Eigen::Index f = 0; f < faces.rows(); ++f) {
    for (int k = 0; k < 3; ++k) {
      if (faces(f, k) < 0 || faces(f, k) >= n) {
        ThrowBadInput(what, "face " + std::to_string(f) + " refers to vertex " + std::to_string(faces(f, k)) +
                                " but there are " + std::to_string(n) + " vertices");
      }
    }
  }
}

Bounds3 ComputeBounds(const Points3& points) {
  Bounds3 b;
  if (points.rows() == 0) return b;
  b.min = points.colwise().minCoeff().transpose();
  b.max = points.colwise().maxCoeff().transpose();
  return b;
}

Eigen::Matrix4d Similarity3::Matrix() const {
  Eigen::Matrix4d M = Eigen::Matrix4d::Identity();
  M.topLeftCorner<3, 3>() = scale * rotation;
  M.topRightCorner<3, 1>() = translation;
  return M;
}

Rigid3 Similarity3::RigidPart() const {
  Rigid3 T = Rigid3::Identity();
  T.linear() = rotation;
  T.translation() = translation;
  return T;
}

Similarity3 Similarity3::Inverse() const {
  Similarity3 inv;
  inv.scale = 1.0 / scale;
  inv.rotation = rotation.transpose();
  inv.translation = -(inv.scale * (inv.rotation * translation));
  return inv;
}

Similarity3 Similarity3::operator*(const Similarity3& other) const {
  Similarity3 T;
  T.scale = scale * other.scale;
  T.rotation = rotation * other.rotation;
  T.translation = scale * (rotation * other.translation) + translation;
  return T;
}

Points3 Similarity3::Apply(const Points3& points) const {
  const Eigen::Matrix3d A = scale * rotation;
  return (points * A.transpose()).rowwise() + translation.transpose();
}

Similarity3 Similarity3::FromRigid(const Rigid3& T) {
  Similarity3 S;
  S.rotation = T.linear();
  S.translation = T.translation();
  return S;
}

Similarity3 Similarity3::FromMatrix(const Eigen::Matrix4d& M, const std::string& what) {
  if (!M.allFinite()) ThrowBadInput(what, "transform has non-finite entries");
  if (M.row(3).head<3>().norm() > 1e-9 || std::abs(M(3, 3) - 1.0) > 1e-9) {
    ThrowBadInput(what, "transform's last row must be [0 0 0 1]");
  }
  const Eigen::Matrix3d A = M.topLeftCorner<3, 3>();
  const double det = A.determinant();
  if (!(det > 0)) ThrowBadInput(what, "transform is a reflection or singular (det <= 0)");
  Similarity3 S;
  S.scale = std::cbrt(det);
  S.rotation = A / S.scale;
  const double orthogonality = (S.rotation.transpose() * S.rotation - Eigen::Matrix3d::Identity()).norm();
  if (orthogonality > 1e-5) {
    ThrowBadInput(what,
                  "transform is not a rotation, uniform scale and translation (shear or non-uniform "
                  "scale: |R^T R - I| = " +
                      std::to_string(orthogonality) + ")");
  }
  S.translation = M.topRightCorner<3, 1>();
  return S;
}

void TransformInPlace(const Similarity3& T, PointCloud* cloud) {
  cloud->positions = T.Apply(cloud->positions);
  if (cloud->has_normals()) cloud->normals = cloud->normals * T.rotation.transpose();
}

void TransformInPlace(const Similarity3& T, TriangleMesh* mesh) { TransformInPlace(T, &mesh->vertices); }

}  // namespace pectus
