// pectus: geometry types. Units are millimetres unless a name says otherwise.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <limits>
#include <map>
#include <numbers>
#include <optional>
#include <string>
#include <vector>

namespace pectus {

/// Radians per degree: `angle_deg * kDegree` is the angle in radians.
inline constexpr double kDegree = std::numbers::pi / 180.0;

/// #rows by 3 matrix of 3D vectors (positions in mm, or unit normals), one row per item.
using Points3 = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;
/// #rows by 3 matrix of 8-bit RGB colours.
using Colors3 = Eigen::Matrix<std::uint8_t, Eigen::Dynamic, 3, Eigen::RowMajor>;
/// #faces by 3 matrix of 0-based vertex indices, counter-clockwise seen from outside.
using Faces3 = Eigen::Matrix<std::int32_t, Eigen::Dynamic, 3, Eigen::RowMajor>;

/// A point cloud: positions, and optionally normals, colours and named per-point scalars.
///
/// Invariant (checked by Validate): every optional attribute is either empty or has one row per point.
struct PointCloud {
  Points3 positions;                               ///< #points by 3, mm
  Points3 normals;                                 ///< empty, or #points by 3, unit length
  Colors3 colors;                                  ///< empty, or #points by 3
  std::map<std::string, Eigen::VectorXd> scalars;  ///< name -> #points values (e.g. "confidence")

  Eigen::Index size() const { return positions.rows(); }
  bool empty() const { return positions.rows() == 0; }
  bool has_normals() const { return normals.rows() > 0; }
  bool has_colors() const { return colors.rows() > 0; }

  /// Throws Error(kBadInput) naming `what` if attribute sizes disagree or a coordinate is not finite.
  void Validate(const std::string& what) const;
  /// Resizes to n points, keeping the attributes that are present (values undefined).
  void Resize(Eigen::Index n);
  /// Appends another cloud; attributes present in only one of them are dropped.
  void Append(const PointCloud& other);
};

/// A triangle mesh: vertices with their attributes, and triangles.
struct TriangleMesh {
  PointCloud vertices;  ///< positions, normals, colours and scalars per vertex
  Faces3 faces;         ///< #faces by 3 vertex indices

  Eigen::Index num_vertices() const { return vertices.size(); }
  Eigen::Index num_faces() const { return faces.rows(); }
  /// Throws Error(kBadInput) naming `what` if a face index is out of range, or as PointCloud::Validate.
  void Validate(const std::string& what) const;
};

/// Axis-aligned bounds of a set of points (mm).
struct Bounds3 {
  Eigen::Vector3d min = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector3d max = Eigen::Vector3d::Constant(-std::numeric_limits<double>::infinity());
  bool empty() const { return (max.array() < min.array()).any(); }
  Eigen::Vector3d extent() const { return empty() ? Eigen::Vector3d::Zero() : Eigen::Vector3d(max - min); }
  double diagonal() const { return extent().norm(); }
};

/// Bounds of the rows of `points` (#points by 3).
Bounds3 ComputeBounds(const Points3& points);

/// A rigid transform T_target_source: x_target = R x_source + t.
using Rigid3 = Eigen::Isometry3d;

/// A similarity transform T_target_source: x_target = s R x_source + t.
struct Similarity3 {
  double scale = 1.0;
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();

  /// The 4 by 4 homogeneous matrix [sR t; 0 1].
  Eigen::Matrix4d Matrix() const;
  /// The rigid part (scale dropped).
  Rigid3 RigidPart() const;
  /// The inverse transform T_source_target.
  Similarity3 Inverse() const;
  /// Applies to one point.
  Eigen::Vector3d operator*(const Eigen::Vector3d& x) const { return scale * (rotation * x) + translation; }
  /// The composition: T_a_b * T_b_c = T_a_c (`other` applied first).
  Similarity3 operator*(const Similarity3& other) const;
  /// Applies to #n by 3 points (mm); returns #n by 3 points.
  Points3 Apply(const Points3& points) const;
  static Similarity3 FromRigid(const Rigid3& T);
  /// Throws Error(kBadInput) naming `what` unless M is [sR t; 0 0 0 1] with R a rotation and s > 0.
  static Similarity3 FromMatrix(const Eigen::Matrix4d& M, const std::string& what);
};

/// Maps positions (and rotates normals) of a cloud in place: x <- T x.
void TransformInPlace(const Similarity3& T, PointCloud* cloud);
/// Maps a mesh's vertices in place; face orientation is kept.
void TransformInPlace(const Similarity3& T, TriangleMesh* mesh);

}  // namespace pectus
