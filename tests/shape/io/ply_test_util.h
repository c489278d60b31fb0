// Helpers shared by the PLY tests (ply_io_test.cc, ply_io_malformed_test.cc): a mesh with exactly
// representable values, the PLY text of a mesh, byte writers and the checks of an error.
#pragma once

#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <string_view>

#include "shape/core/error.h"
#include "shape/io/format_parsers.h"
#include "shape/io/mesh_io.h"

namespace pectus::testing {

/// A small mesh whose every value is exactly representable as float (and colours as uchar):
/// 6 vertices with normals, colours and two scalars, 4 triangles.
inline TriangleMesh MakeMesh() {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> coordinate(-300.0f, 300.0f), unit(-1.0f, 1.0f), score(0.0f, 1.0f);
  TriangleMesh mesh;
  const int n = 6;
  mesh.vertices.positions.resize(n, 3);
  mesh.vertices.normals.resize(n, 3);
  mesh.vertices.colors.resize(n, 3);
  Eigen::VectorXd confidence(n), intensity(n);
  for (int i = 0; i < n; ++i) {
    for (int k = 0; k < 3; ++k) {
      mesh.vertices.positions(i, k) = coordinate(rng);
      mesh.vertices.normals(i, k) = unit(rng);
      mesh.vertices.colors(i, k) = static_cast<std::uint8_t>(40 * i + 7 * k);
    }
    confidence(i) = score(rng);
    intensity(i) = 1000.0f * score(rng);
  }
  mesh.vertices.scalars["confidence"] = confidence;
  mesh.vertices.scalars["intensity"] = intensity;
  mesh.faces.resize(4, 3);
  mesh.faces << 0, 1, 2, 0, 2, 3, 3, 4, 5, 5, 1, 0;
  return mesh;
}

inline std::string ToPly(const TriangleMesh& mesh, bool binary, const std::string& comment = "") {
  std::ostringstream out;
  WriteOptions options;
  options.binary = binary;
  options.comment = comment;
  WritePly(out, mesh, options);
  return out.str();
}

inline void ExpectSameMesh(const TriangleMesh& expected, const TriangleMesh& actual) {
  ASSERT_EQ(actual.num_vertices(), expected.num_vertices());
  EXPECT_EQ(actual.vertices.positions, expected.vertices.positions);
  EXPECT_EQ(actual.vertices.normals, expected.vertices.normals);
  EXPECT_EQ(actual.vertices.colors, expected.vertices.colors);
  ASSERT_EQ(actual.vertices.scalars.size(), expected.vertices.scalars.size());
  for (const auto& [name, values] : expected.vertices.scalars) {
    ASSERT_EQ(actual.vertices.scalars.count(name), 1u) << name;
    EXPECT_EQ(actual.vertices.scalars.at(name), values) << name;
  }
  EXPECT_EQ(actual.faces, expected.faces);
}

/// Parsing `bytes` must throw Error(kBadInput) whose message names `file` and contains `phrase`.
inline void ExpectBadInput(std::string_view bytes, const std::string& file, const std::string& phrase) {
  try {
    ParsePly(bytes, file);
    ADD_FAILURE() << file << ": parsed without error, expected '" << phrase << "'";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::kBadInput) << e.what();
    EXPECT_NE(std::string(e.what()).find(file), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(phrase), std::string::npos)
        << e.what() << "\n  expected: " << phrase;
  }
}

/// The line number an error reports, or -1 if parsing succeeded.
inline std::int64_t ErrorLine(std::string_view bytes) {
  try {
    ParsePly(bytes, "line.ply");
  } catch (const Error& e) {
    return e.line();
  }
  return -1;
}

template <typename T>
void PutBigEndian(std::string* out, T value) {
  char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));
  if constexpr (std::endian::native == std::endian::little) std::reverse(bytes, bytes + sizeof(T));
  out->append(bytes, sizeof(T));
}

template <typename T>
void PutLittleEndian(std::string* out, T value) {
  char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));
  if constexpr (std::endian::native == std::endian::big) std::reverse(bytes, bytes + sizeof(T));
  out->append(bytes, sizeof(T));
}

inline const char kAsciiCloud[] =
    "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
    "end_header\n";

}  // namespace pectus::testing
