// The files of the PLY benchmark (io_benchmark.cc): pectus's own writer's (a 1M-point cloud with normals
// and a 1M-vertex mesh, each ASCII and binary, written once into the temporary folder) and third-party
// files read in place (the Stanford bunny: a raw range scan and the zippered reference mesh, ASCII, from
// /work/shared/datasets/stanford_bunny/, whose SOURCE.md gives their origin). Included once, by
// io_benchmark.cc.
#pragma once

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <string>

#include "shape/io/format_parsers.h"
#include "shape/io/mapped_file.h"
#include "shape/io/mesh_io.h"
#include "tests/support/shared_data.h"

namespace pectus {
namespace {

/// 1M points on a 300 mm x 200 mm wavy patch (a chest-sized surface), with unit normals.
TriangleMesh MakeCloud() {
  const int n = 1'000'000;
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  TriangleMesh cloud;
  cloud.vertices.positions.resize(n, 3);
  cloud.vertices.normals.resize(n, 3);
  for (int i = 0; i < n; ++i) {
    const double x = 150.0 * u(rng), y = 100.0 * u(rng);
    const double z = 20.0 * std::sin(x / 40.0) * std::cos(y / 30.0) + 0.2 * u(rng);
    const Eigen::Vector3d normal = Eigen::Vector3d(-0.5 * std::cos(x / 40.0) * std::cos(y / 30.0),
                                                   0.666 * std::sin(x / 40.0) * std::sin(y / 30.0), 1.0)
                                       .normalized();
    cloud.vertices.positions.row(i) << x, y, z;
    cloud.vertices.normals.row(i) = normal.transpose();
  }
  cloud.faces.resize(0, 3);
  return cloud;
}

/// A 1000 x 1000 grid of vertices on the same patch, two triangles per cell.
TriangleMesh MakeMesh() {
  const int side = 1000;
  TriangleMesh mesh;
  mesh.vertices.positions.resize(side * side, 3);
  for (int r = 0; r < side; ++r) {
    for (int c = 0; c < side; ++c) {
      const double x = 0.3 * c - 150.0, y = 0.2 * r - 100.0;
      mesh.vertices.positions.row(r * side + c) << x, y, 20.0 * std::sin(x / 40.0) * std::cos(y / 30.0);
    }
  }
  mesh.faces.resize(2 * (side - 1) * (side - 1), 3);
  Eigen::Index f = 0;
  for (int r = 0; r + 1 < side; ++r) {
    for (int c = 0; c + 1 < side; ++c) {
      const int v = r * side + c;
      mesh.faces.row(f++) << v, v + 1, v + side + 1;
      mesh.faces.row(f++) << v, v + side + 1, v + side;
    }
  }
  return mesh;
}

std::string ToPly(const TriangleMesh& mesh, bool binary) {
  std::ostringstream out;
  WriteOptions options;
  options.binary = binary;
  WritePly(out, mesh, options);
  return std::move(out).str();
}

const TriangleMesh& Cloud() {
  static const TriangleMesh cloud = MakeCloud();
  return cloud;
}
const TriangleMesh& Mesh() {
  static const TriangleMesh mesh = MakeMesh();
  return mesh;
}

enum class Input { kCloudAscii, kCloudBinary, kMeshAscii, kMeshBinary, kBunnyScan, kBunnyMesh };

/// Faces to read (a mesh), or a point cloud.
bool IsMesh(Input input) {
  return input == Input::kMeshAscii || input == Input::kMeshBinary || input == Input::kBunnyMesh;
}
/// Written by pectus's own writer (else a third party's file).
bool IsOurs(Input input) { return input != Input::kBunnyScan && input != Input::kBunnyMesh; }

/// The third-party files, read in place: bun000.ply (a raw range scan, 40 256 points and a range_grid
/// element to skip) and reconstruction/bun_zipper.ply (35 947 vertices, 69 451 triangles), both ASCII, in
/// metres.
std::string BunnyPath(Input input) {
  const std::string dir = testing_support::SharedPath("datasets/stanford_bunny/");
  return dir + (input == Input::kBunnyScan ? "bun000.ply" : "reconstruction/bun_zipper.ply");
}

/// The file's bytes, in memory (generated once per input, or read once from the third party's file).
const std::string& Bytes(Input input) {
  static std::string bytes[6];
  std::string& b = bytes[static_cast<int>(input)];
  if (!b.empty()) return b;
  switch (input) {
    case Input::kCloudAscii: b = ToPly(Cloud(), false); break;
    case Input::kCloudBinary: b = ToPly(Cloud(), true); break;
    case Input::kMeshAscii: b = ToPly(Mesh(), false); break;
    case Input::kMeshBinary: b = ToPly(Mesh(), true); break;
    default: b = std::string(MappedFile(BunnyPath(input)).bytes()); break;
  }
  return b;
}

/// Where this process writes our file of `input` (removed at the end by RemoveTempFiles).
std::filesystem::path TempPath(Input input) {
  return std::filesystem::temp_directory_path() / ("pectus_io_bench_" + std::to_string(::getpid()) + "_" +
                                                   std::to_string(static_cast<int>(input)) + ".ply");
}

/// The file: ours written once into the temporary folder (then warm in the page cache, as the
/// third-party files are after their first read); the bunny's in place.
std::string Path(Input input) {
  if (!IsOurs(input)) return BunnyPath(input);
  const auto path = TempPath(input);
  if (!std::filesystem::exists(path) || std::filesystem::file_size(path) != Bytes(input).size()) {
    std::ofstream(path, std::ios::binary) << Bytes(input);
  }
  return path.string();
}

/// Removes the files Path() wrote.
void RemoveTempFiles() {
  for (const Input input : {Input::kCloudAscii, Input::kCloudBinary, Input::kMeshAscii, Input::kMeshBinary}) {
    std::error_code ec;
    std::filesystem::remove(TempPath(input), ec);
  }
}

/// How pectus reads the file, as a user would: the bunny in its unit (metres, scaled to mm), ours in mm.
ReadOptions OptionsFor(Input input) {
  ReadOptions options;
  if (!IsOurs(input)) options.input_units = LengthUnit::kMetre;
  return options;
}

}  // namespace
}  // namespace pectus
