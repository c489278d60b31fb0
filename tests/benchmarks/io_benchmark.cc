// Benchmark of the PLY reader and writer: bytes per second for ASCII and binary files held in memory
// (a 1M-point cloud with normals, a 1M-vertex / 2M-triangle mesh) and for a real Stanford bunny sweep
// (ASCII, with a range_grid element to skip). Run:
//   cmake --build build --target io_benchmark && build/tests/benchmarks/io_benchmark
#include <benchmark/benchmark.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <string>

#include <pcl/io/ply_io.h>
#include <pcl/point_types.h>

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

enum class Input { kCloudAscii, kCloudBinary, kMeshAscii, kMeshBinary };

const std::string& Bytes(Input input) {
  static const std::string cloud_ascii = ToPly(Cloud(), false), cloud_binary = ToPly(Cloud(), true);
  static const std::string mesh_ascii = ToPly(Mesh(), false), mesh_binary = ToPly(Mesh(), true);
  switch (input) {
    case Input::kCloudAscii: return cloud_ascii;
    case Input::kCloudBinary: return cloud_binary;
    case Input::kMeshAscii: return mesh_ascii;
    case Input::kMeshBinary: break;
  }
  return mesh_binary;
}

void BM_ParsePly(benchmark::State& state, Input input) {
  const std::string& bytes = Bytes(input);
  for (auto _ : state) {
    TriangleMesh mesh = ParsePly(bytes, "bench.ply");
    benchmark::DoNotOptimize(mesh.vertices.positions.data());
  }
  state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations()) * static_cast<std::int64_t>(bytes.size()));
  state.counters["file_MB"] = static_cast<double>(bytes.size()) / 1e6;
}

void BM_ParsePlyBunny(benchmark::State& state) {
  const MappedFile file(testing_support::BunnyDirectory() + "bun000.ply");
  for (auto _ : state) {
    TriangleMesh mesh = ParsePly(file.bytes(), file.path());
    benchmark::DoNotOptimize(mesh.vertices.positions.data());
  }
  state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations()) *
                          static_cast<std::int64_t>(file.bytes().size()));
  state.counters["file_MB"] = static_cast<double>(file.bytes().size()) / 1e6;
}

void BM_WritePly(benchmark::State& state, Input input) {
  const bool binary = input == Input::kCloudBinary || input == Input::kMeshBinary;
  const TriangleMesh& mesh = (input == Input::kCloudAscii || input == Input::kCloudBinary) ? Cloud() : Mesh();
  std::size_t size = 0;
  for (auto _ : state) {
    size = ToPly(mesh, binary).size();
    benchmark::ClobberMemory();
  }
  state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations()) * static_cast<std::int64_t>(size));
}

// The peer: PCL's PLY reader on the same bytes (from a file in the temporary folder, warm in the page
// cache; pectus's own ReadMesh on the same file is measured beside it, so the two include the same I/O).
std::string TempFile(Input input) {
  const auto path = std::filesystem::temp_directory_path() /
                    ("pectus_io_bench_" + std::to_string(static_cast<int>(input)) + ".ply");
  if (!std::filesystem::exists(path)) {
    std::ofstream(path, std::ios::binary) << Bytes(input);
  }
  return path.string();
}

void BM_ReadMeshFile(benchmark::State& state, Input input) {
  const std::string path = TempFile(input);
  for (auto _ : state) {
    TriangleMesh mesh = ReadMesh(path);
    benchmark::DoNotOptimize(mesh.vertices.positions.data());
  }
  state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations()) *
                          static_cast<std::int64_t>(Bytes(input).size()));
}

void BM_PclLoadPly(benchmark::State& state, Input input) {
  const std::string path = TempFile(input);
  for (auto _ : state) {
    pcl::PointCloud<pcl::PointNormal> cloud;
    pcl::PLYReader reader;
    if (reader.read(path, cloud) != 0) state.SkipWithError("PCL could not read the file");
    benchmark::DoNotOptimize(cloud.points.data());
  }
  state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations()) *
                          static_cast<std::int64_t>(Bytes(input).size()));
}

BENCHMARK_CAPTURE(BM_ReadMeshFile, cloud_ascii, Input::kCloudAscii)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_PclLoadPly, cloud_ascii, Input::kCloudAscii)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_ReadMeshFile, cloud_binary, Input::kCloudBinary)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_PclLoadPly, cloud_binary, Input::kCloudBinary)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_ParsePly, cloud_ascii, Input::kCloudAscii)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_ParsePly, cloud_binary, Input::kCloudBinary)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_ParsePly, mesh_ascii, Input::kMeshAscii)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_ParsePly, mesh_binary, Input::kMeshBinary)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ParsePlyBunny)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_WritePly, cloud_ascii, Input::kCloudAscii)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_WritePly, cloud_binary, Input::kCloudBinary)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_WritePly, mesh_binary, Input::kMeshBinary)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace pectus

// BENCHMARK_MAIN(), after checking for the shared bunny sweep BM_ParsePlyBunny reads.
int main(int argc, char** argv) {
  if (!pectus::testing_support::HaveSharedFile("io_benchmark", "datasets/stanford_bunny/bun000.ply"))
    return 3;
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
