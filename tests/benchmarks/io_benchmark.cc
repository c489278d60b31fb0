// Benchmark of the PLY reader and writer against PCL 1.13, like with like:
//   file    pectus ReadPointCloud / ReadMesh of a file (mapping, parse, validation, units) against
//           pcl::io::loadPLYFile of the same file (into PointCloud<PointNormal>, <PointXYZ> for the
//           bunny scan that has no normals, or PolygonMesh for a mesh);
//   memory  pectus ParsePly of the same bytes held in memory. PCL has no in-memory PLY reader (PLYReader
//           and ply_parser take only a file name), so there is no PCL memory row: a memory figure is never
//           divided by a PCL file figure.
// Inputs: files of pectus's own writer (a 1M-point cloud with normals and a 1M-vertex / 2M-triangle mesh,
// ASCII and binary) and third-party files (the Stanford bunny's raw scan bun000.ply and its zippered mesh
// bun_zipper.ply, ASCII; see io_benchmark_inputs.h). After the runs, a table of ratios (CPU time, the
// median of the repetitions when there are several): PCL's file read over pectus's, and pectus's file read
// over its memory parse (the cost of the file and its checks). Run:
//   cmake --build build --target io_benchmark && build/tests/benchmarks/io_benchmark
//   --benchmark_repetitions=3 (quick check: --benchmark_filter=bunny --benchmark_min_time=0.01)
#include <benchmark/benchmark.h>
#include <pcl/PolygonMesh.h>
#include <pcl/console/print.h>
#include <pcl/io/ply_io.h>
#include <pcl/point_types.h>
#include <unistd.h>

#include <cstdio>
#include <iostream>
#include <map>
#include <string>
#include <vector>

#include "tests/benchmarks/io_benchmark_inputs.h"
#include "tests/support/shared_data.h"

namespace pectus {
namespace {

void CountBytes(benchmark::State& state, Input input) {
  const std::size_t size = Bytes(input).size();
  state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations()) * static_cast<std::int64_t>(size));
  state.counters["file_MB"] = static_cast<double>(size) / 1e6;
}

// pectus from the file: ReadMesh (with faces) for a mesh, ReadPointCloud for a point cloud.
void BM_FilePectus(benchmark::State& state, Input input) {
  const std::string path = Path(input);
  const ReadOptions options = OptionsFor(input);
  for (auto _ : state) {
    if (IsMesh(input)) {
      TriangleMesh mesh = ReadMesh(path, options);
      benchmark::DoNotOptimize(mesh.faces.data());
    } else {
      PointCloud cloud = ReadPointCloud(path, options);
      benchmark::DoNotOptimize(cloud.positions.data());
    }
  }
  CountBytes(state, input);
}

// PCL from the same file: pcl::io::loadPLYFile.
void BM_FilePcl(benchmark::State& state, Input input) {
  const std::string path = Path(input);
  for (auto _ : state) {
    int status = 0;
    if (IsMesh(input)) {
      pcl::PolygonMesh mesh;
      status = pcl::io::loadPLYFile(path, mesh);
      benchmark::DoNotOptimize(mesh.polygons.data());
    } else if (IsOurs(input)) {
      pcl::PointCloud<pcl::PointNormal> cloud;
      status = pcl::io::loadPLYFile(path, cloud);
      benchmark::DoNotOptimize(cloud.points.data());
    } else {
      pcl::PointCloud<pcl::PointXYZ> cloud;
      status = pcl::io::loadPLYFile(path, cloud);
      benchmark::DoNotOptimize(cloud.points.data());
    }
    if (status != 0) state.SkipWithError("PCL could not read the file");
  }
  CountBytes(state, input);
}

// pectus from memory: the parser alone on the file's bytes.
void BM_MemoryPectus(benchmark::State& state, Input input) {
  const std::string& bytes = Bytes(input);
  for (auto _ : state) {
    TriangleMesh mesh = ParsePly(bytes, "bench.ply");
    benchmark::DoNotOptimize(mesh.vertices.positions.data());
  }
  CountBytes(state, input);
}

// pectus's writer, into memory.
void BM_WritePly(benchmark::State& state, Input input) {
  const bool binary = input == Input::kCloudBinary || input == Input::kMeshBinary;
  const TriangleMesh& mesh = IsMesh(input) ? Mesh() : Cloud();
  std::size_t size = 0;
  for (auto _ : state) {
    size = ToPly(mesh, binary).size();
    benchmark::ClobberMemory();
  }
  state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations()) * static_cast<std::int64_t>(size));
}

#define PECTUS_READS(name, input)                                               \
  BENCHMARK_CAPTURE(BM_FilePectus, name, input)->Unit(benchmark::kMillisecond); \
  BENCHMARK_CAPTURE(BM_FilePcl, name, input)->Unit(benchmark::kMillisecond);    \
  BENCHMARK_CAPTURE(BM_MemoryPectus, name, input)->Unit(benchmark::kMillisecond)
PECTUS_READS(bunny_scan_ascii, Input::kBunnyScan);
PECTUS_READS(bunny_mesh_ascii, Input::kBunnyMesh);
PECTUS_READS(cloud_ascii, Input::kCloudAscii);
PECTUS_READS(cloud_binary, Input::kCloudBinary);
PECTUS_READS(mesh_ascii, Input::kMeshAscii);
PECTUS_READS(mesh_binary, Input::kMeshBinary);
#undef PECTUS_READS
BENCHMARK_CAPTURE(BM_WritePly, cloud_ascii, Input::kCloudAscii)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_WritePly, cloud_binary, Input::kCloudBinary)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_WritePly, mesh_binary, Input::kMeshBinary)->Unit(benchmark::kMillisecond);

// The console table as usual, then the ratios: for every input, the CPU time per read of each route (the
// median aggregate when repeated), PCL file / pectus file, and pectus file / pectus memory.
class RatioReporter : public benchmark::ConsoleReporter {
 public:
  RatioReporter() : ConsoleReporter(::isatty(STDOUT_FILENO) ? OO_Color : OO_None) {}

  void ReportRuns(const std::vector<Run>& runs) override {
    ConsoleReporter::ReportRuns(runs);
    for (const Run& run : runs) {
      if (run.error_occurred) continue;
      const bool median = run.run_type == Run::RT_Aggregate && run.aggregate_name == "median";
      if (run.run_type == Run::RT_Aggregate && !median) continue;
      const std::string name = run.run_name.str();  // "BM_FilePcl/cloud_ascii"
      const auto slash = name.find('/');
      if (slash == std::string::npos) continue;
      double& slot = ms_[name.substr(slash + 1)][name.substr(0, slash)];
      if (median || slot == 0.0) slot = run.GetAdjustedCPUTime();  // a median replaces single runs
    }
  }

  void Finalize() override {
    std::FILE* out = stdout;
    std::fprintf(out,
                 "\nratios (CPU ms per read; PCL has no in-memory PLY reader, so memory is pectus only)\n"
                 "%-18s %12s %12s %14s %16s %18s\n",
                 "input", "pectus file", "PCL file", "pectus memory", "PCL / pectus file",
                 "pectus file / memory");
    for (const auto& [input, routes] : ms_) {
      const auto& by = routes;  // clang 14 captures no structured binding in a lambda
      auto get = [&](const char* route) {
        const auto it = by.find(route);
        return it == by.end() ? 0.0 : it->second;
      };
      const double file = get("BM_FilePectus"), pcl = get("BM_FilePcl"), memory = get("BM_MemoryPectus");
      if (file == 0.0 && memory == 0.0) continue;  // the writer's rows
      std::fprintf(out, "%-18s %12.2f %12.2f %14.2f %16.2fx %17.2fx\n", input.c_str(), file, pcl, memory,
                   file > 0.0 ? pcl / file : 0.0, memory > 0.0 ? file / memory : 0.0);
    }
    std::fflush(out);
  }

 private:
  std::map<std::string, std::map<std::string, double>> ms_;  // input -> route -> CPU ms per read
};

}  // namespace
}  // namespace pectus

int main(int argc, char** argv) {
  for (const char* bunny :
       {"datasets/stanford_bunny/bun000.ply", "datasets/stanford_bunny/reconstruction/bun_zipper.ply"}) {
    if (!pectus::testing_support::HaveSharedFile("io_benchmark", bunny)) return 3;
  }
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  // PCL warns on every read of a cloud without its PointNormal's `curvature` field: errors only.
  pcl::console::setVerbosityLevel(pcl::console::L_ERROR);
  pectus::RatioReporter reporter;
  benchmark::RunSpecifiedBenchmarks(&reporter);
  benchmark::Shutdown();
  pectus::RemoveTempFiles();
  return 0;
}
