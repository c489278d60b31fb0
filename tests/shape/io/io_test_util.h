// Helpers shared by the shape/io tests: a temporary folder, a test mesh with known geometry, and a check
// that a call throws pectus::Error(kBadInput) with a given phrase and file name.
#pragma once

#include <gtest/gtest.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <string>
#include <string_view>

#include "shape/core/error.h"
#include "shape/core/geometry.h"

namespace pectus::testing {

/// A fresh folder under the system's temporary folder, removed with everything in it on destruction.
class TempDir {
 public:
  TempDir() {
    static std::atomic<int> counter{0};
    const auto now = std::chrono::steady_clock::now().time_since_epoch().count();
    path_ = std::filesystem::temp_directory_path() / ("pectus-io-test-" + std::to_string(::getpid()) + "-" +
                                                      std::to_string(now) + "-" + std::to_string(counter++));
    std::filesystem::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;

  const std::filesystem::path& path() const { return path_; }
  std::filesystem::path operator/(const std::string& name) const { return path_ / name; }

  /// Writes `bytes` to a file of this folder and returns its path.
  std::filesystem::path Write(const std::string& name, std::string_view bytes) const {
    const std::filesystem::path p = path_ / name;
    std::ofstream out(p, std::ios::binary);
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    return p;
  }

 private:
  std::filesystem::path path_;
};

/// Success if `f()` throws pectus::Error of kind kBadInput whose what() contains `phrase` and whose file
/// contains `file` (and, when `line` > 0, whose line is `line`).
template <typename F>
::testing::AssertionResult ThrowsBadInput(F&& f, std::string_view phrase, std::string_view file,
                                          std::int64_t line = 0) {
  try {
    f();
  } catch (const Error& e) {
    const std::string what = e.what();
    if (e.kind() != ErrorKind::kBadInput) {
      return ::testing::AssertionFailure()
             << "kind " << static_cast<int>(e.kind()) << ", not kBadInput: " << what;
    }
    if (what.find(phrase) == std::string::npos) {
      return ::testing::AssertionFailure() << "message lacks \"" << phrase << "\": " << what;
    }
    if (e.file().find(file) == std::string::npos || what.find(file) == std::string::npos) {
      return ::testing::AssertionFailure() << "error does not name the file \"" << file << "\": " << what;
    }
    if (line > 0 && e.line() != line) {
      return ::testing::AssertionFailure() << "line " << e.line() << ", expected " << line << ": " << what;
    }
    return ::testing::AssertionSuccess() << what;
  } catch (const std::exception& e) {
    return ::testing::AssertionFailure() << "threw something other than pectus::Error: " << e.what();
  }
  return ::testing::AssertionFailure() << "did not throw";
}

/// A UV sphere of radius `r` mm about `c` with `rings` latitude bands and `segments` longitudes: outward
/// unit normals, colours from the position, and a scalar "height" (z - c.z). Faces counter-clockwise seen
/// from outside. (rings - 1) * segments + 2 vertices, 2 * (rings - 1) * segments triangles.
inline TriangleMesh MakeSphere(double r = 100.0, const Eigen::Vector3d& c = Eigen::Vector3d(10, -20, 30),
                               int rings = 8, int segments = 12) {
  const int nv = (rings - 1) * segments + 2;
  TriangleMesh mesh;
  PointCloud& v = mesh.vertices;
  v.positions.resize(nv, 3);
  v.normals.resize(nv, 3);
  v.colors.resize(nv, 3);
  Eigen::VectorXd height(nv);
  const auto add = [&](int i, const Eigen::Vector3d& n) {
    v.normals.row(i) = n.transpose();
    v.positions.row(i) = (c + r * n).transpose();
    for (int k = 0; k < 3; ++k) v.colors(i, k) = static_cast<std::uint8_t>(std::lround(127.5 * (n[k] + 1.0)));
    height[i] = r * n.z();
  };
  add(0, Eigen::Vector3d::UnitZ());
  for (int i = 1; i < rings; ++i) {
    const double theta = std::numbers::pi * i / rings;
    for (int j = 0; j < segments; ++j) {
      const double phi = 2 * std::numbers::pi * j / segments;
      add(1 + (i - 1) * segments + j,
          Eigen::Vector3d(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta)));
    }
  }
  add(nv - 1, -Eigen::Vector3d::UnitZ());
  v.scalars["height"] = height;
  const auto ring = [&](int i, int j) { return 1 + (i - 1) * segments + (j % segments); };
  std::vector<Eigen::Vector3i> faces;
  for (int j = 0; j < segments; ++j) faces.emplace_back(0, ring(1, j), ring(1, j + 1));
  for (int i = 1; i + 1 < rings; ++i) {
    for (int j = 0; j < segments; ++j) {
      faces.emplace_back(ring(i, j), ring(i + 1, j), ring(i + 1, j + 1));
      faces.emplace_back(ring(i, j), ring(i + 1, j + 1), ring(i, j + 1));
    }
  }
  for (int j = 0; j < segments; ++j) faces.emplace_back(nv - 1, ring(rings - 1, j + 1), ring(rings - 1, j));
  mesh.faces.resize(static_cast<Eigen::Index>(faces.size()), 3);
  for (std::size_t f = 0; f < faces.size(); ++f)
    mesh.faces.row(static_cast<Eigen::Index>(f)) = faces[f].transpose();
  return mesh;
}

/// Largest distance between corresponding triangle corners of two meshes with the same faces in the same
/// order (vertex numbering may differ, as after an STL round trip); infinity if the face counts differ.
inline double MaxCornerDistance(const TriangleMesh& a, const TriangleMesh& b) {
  if (a.num_faces() != b.num_faces()) return std::numeric_limits<double>::infinity();
  double worst = 0;
  for (Eigen::Index f = 0; f < a.num_faces(); ++f) {
    for (int k = 0; k < 3; ++k) {
      const Eigen::RowVector3d pa = a.vertices.positions.row(a.faces(f, k));
      const Eigen::RowVector3d pb = b.vertices.positions.row(b.faces(f, k));
      worst = std::max(worst, (pa - pb).norm());
    }
  }
  return worst;
}

}  // namespace pectus::testing
