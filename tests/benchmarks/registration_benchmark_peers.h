// pectus registration benchmark (issue 4): the peers. PCL IterativeClosestPointWithNormals in this
// process, Open3D registration_icp (point-to-plane or generalized ICP) through
// scripts/peers/open3d_icp.py with /usr/bin/python3. Both run "stages" (one stage = plain ICP with one gate
// on a nested random subset of the source). Included once, by registration_benchmark.cc.
#pragma once

#include <omp.h>
// GCC 12 misreports -Warray-bounds and -Wuse-after-free inside PCL's ICP templates and the Eigen code they
// inline (SSE loads of 3-vectors): silenced for these PCL headers only, not for the benchmark's own code.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Warray-bounds"
#if defined(__GNUC__) && !defined(__clang__)  // clang has no -Wuse-after-free group
#pragma GCC diagnostic ignored "-Wuse-after-free"
#endif
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/registration/icp.h>
#pragma GCC diagnostic pop

#include <sys/resource.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "registration/random_sample.h"
#include "shape/io/mesh_io.h"
#include "shape/io/transform_io.h"
#include "tests/benchmarks/registration_benchmark_data.h"

namespace pectus {
namespace {

namespace fs = std::filesystem;

struct Stage {
  double gate_mm;
  int points;  // 0: every point
};

std::string StagesText(const std::vector<Stage>& stages) {
  std::string s;
  for (const Stage& st : stages)
    s += (s.empty() ? "" : ",") + std::to_string(st.gate_mm) + ":" + std::to_string(st.points);
  return s;
}

// The wall time of a command run through the shell and the CPU time of everything it ran (all threads,
// the shell included: the children's rusage), with its exit status.
struct ProcessTime {
  double wall_s = 0.0, cpu_s = 0.0;
  int status = -1;
};

ProcessTime RunProcess(const std::string& command) {
  auto children_cpu = [] {
    rusage u{};
    getrusage(RUSAGE_CHILDREN, &u);
    return static_cast<double>(u.ru_utime.tv_sec + u.ru_stime.tv_sec) +
           1e-6 * static_cast<double>(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
  };
  ProcessTime t;
  const double c0 = children_cpu();
  const auto t0 = Clock::now();
  t.status = std::system(command.c_str());
  t.wall_s = Since(t0);
  t.cpu_s = children_cpu() - c0;
  return t;
}

// One peer's run: its figures and the pose it found.
struct PeerRun {
  json figures;
  Rigid3 T = Rigid3::Identity();
};

pcl::PointCloud<pcl::PointNormal>::Ptr ToPcl(const Points3& x, const Points3& n,
                                             const std::vector<std::uint32_t>* rows = nullptr) {
  auto cloud = std::make_shared<pcl::PointCloud<pcl::PointNormal>>();
  const std::size_t m = rows ? rows->size() : static_cast<std::size_t>(x.rows());
  cloud->resize(m);
  for (std::size_t k = 0; k < m; ++k) {
    const Eigen::Index i = rows ? (*rows)[k] : static_cast<Eigen::Index>(k);
    pcl::PointNormal& p = (*cloud)[k];
    p.x = static_cast<float>(x(i, 0));
    p.y = static_cast<float>(x(i, 1));
    p.z = static_cast<float>(x(i, 2));
    p.normal_x = static_cast<float>(n(i, 0));
    p.normal_y = static_cast<float>(n(i, 1));
    p.normal_z = static_cast<float>(n(i, 2));
  }
  return cloud;
}

// PCL, staged like pectus's levels. The source subsets are made before timing; the target's k-d tree is
// built once inside the timed region (PCL builds it lazily on the first align). PCL works in float, so the
// clouds are given centred on the target's centroid (the bunny's frame is in metres read as mm, near the
// origin, the chests are not).
PeerRun RunPcl(const Points3& target_x, const Points3& nt, const Points3& source_x, const Points3& ns,
               const Rigid3& start, const std::vector<Stage>& stages, int max_iterations, int repeat) {
  const Eigen::Vector3d origin = target_x.colwise().mean().transpose();
  const Points3 centred = target_x.rowwise() - origin.transpose();
  const auto target = ToPcl(centred, nt);
  std::vector<std::uint32_t> all(static_cast<std::size_t>(source_x.rows()));
  for (std::size_t i = 0; i < all.size(); ++i) all[i] = static_cast<std::uint32_t>(i);
  const std::vector<std::uint32_t> shuffled = RandomSample(all, all.size(), 1);
  std::vector<pcl::PointCloud<pcl::PointNormal>::Ptr> sources;
  for (const Stage& st : stages) {
    const std::size_t n = st.points > 0 && st.points < static_cast<int>(all.size())
                              ? static_cast<std::size_t>(st.points)
                              : all.size();
    std::vector<std::uint32_t> rows(shuffled.begin(), shuffled.begin() + static_cast<std::ptrdiff_t>(n));
    std::sort(rows.begin(), rows.end());
    sources.push_back(ToPcl(source_x, ns, &rows));
  }
  Rigid3 shift = Rigid3::Identity();
  shift.translation() = -origin;
  const Eigen::Matrix4f start_centred = (shift * start).matrix().cast<float>();
  std::vector<double> times, cpu;
  Eigen::Matrix4f T = start_centred;
  int iterations = 0;
  for (int k = 0; k < repeat; ++k) {
    T = start_centred;
    iterations = 0;
    pcl::IterativeClosestPointWithNormals<pcl::PointNormal, pcl::PointNormal> icp;
    const double c0 = CpuSeconds();
    const auto t0 = Clock::now();
    icp.setInputTarget(target);
    for (std::size_t s = 0; s < stages.size(); ++s) {
      icp.setInputSource(sources[s]);
      icp.setMaxCorrespondenceDistance(stages[s].gate_mm);
      icp.setMaximumIterations(max_iterations);
      icp.setTransformationEpsilon(2e-3 * 2e-3);  // squared translation of an update, mm^2 (as pectus)
      icp.setTransformationRotationEpsilon(std::cos(1e-3 * M_PI / 180.0));  // cosine (as pectus)
      icp.setEuclideanFitnessEpsilon(1e-6);  // relative change of the MSE (as Open3D below)
      pcl::PointCloud<pcl::PointNormal> aligned;
      icp.align(aligned, T);
      T = icp.getFinalTransformation();
      iterations += icp.nr_iterations_;
    }
    times.push_back(Since(t0));
    cpu.push_back(CpuSeconds() - c0);
  }
  PeerRun run;
  run.T.matrix() = T.cast<double>();
  run.T.linear() = Eigen::Quaterniond(run.T.linear()).normalized().toRotationMatrix();  // float
  run.T = shift.inverse() * run.T;
  run.figures = {{"seconds_median", Median(times)},
                 {"seconds_best", *std::min_element(times.begin(), times.end())},
                 {"cpu_seconds_median", Median(cpu)},
                 {"iterations", iterations},
                 {"stages", StagesText(stages)},
                 {"threads", 1},
                 {"method", "pcl::IterativeClosestPointWithNormals (point-to-plane LLS, float), " +
                                std::to_string(max_iterations) + " iterations max per stage"}};
  return run;
}

// Writes the inputs of open3d_icp.py into `dir`: target.ply and source.ply with normals, init.json.
void WriteOpen3dInputs(const fs::path& dir, const Points3& target_x, const Points3& nt,
                       const Points3& source_x, const Points3& ns, const Rigid3& start) {
  fs::create_directories(dir);
  PointCloud t, s;
  t.positions = target_x;
  t.normals = nt;
  s.positions = source_x;
  s.normals = ns;
  WritePointCloud(dir / "target.ply", t);
  WritePointCloud(dir / "source.ply", s);
  WriteTransformJson(dir / "init.json", Similarity3::FromRigid(start));
}

// Open3D on the inputs in `dir`; method "point-to-plane" or "generalized" (generalized ICP, Segal et al.
// 2009, its covariances from each cloud's own neighbourhoods).
PeerRun RunOpen3d(const fs::path& dir, const std::vector<Stage>& stages, int max_iterations, int repeat,
                  const std::string& method = "point-to-plane") {
  const std::string script = std::string(PECTUS_SOURCE_DIR) + "/scripts/peers/open3d_icp.py";
  const fs::path out = dir / "open3d.json";
  const std::string cmd = "/usr/bin/python3 " + script + " " + (dir / "target.ply").string() + " " +
                          (dir / "source.ply").string() + " " + (dir / "init.json").string() + " --stages " +
                          StagesText(stages) + " --max-iterations " + std::to_string(max_iterations) +
                          " --repeat " + std::to_string(repeat) + " --method " + method + " > " +
                          out.string();
  PeerRun run;
  const ProcessTime process = RunProcess(cmd);
  if (process.status != 0) {
    run.figures = {{"error", "command failed: " + cmd}};
    return run;
  }
  std::ifstream in(out);
  const json o = json::parse(in);
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) run.T.matrix()(i, j) = o["T_target_source"][i][j].get<double>();
  run.figures = {
      {"seconds_median", o["seconds_median"]},
      {"seconds_best", o["seconds_best"]},
      {"cpu_seconds_median", o["cpu_seconds_median"]},
      {"process_seconds", process.wall_s},
      {"process_cpu_seconds", process.cpu_s},
      {"fitness", o["fitness"]},
      {"inlier_rmse_mm", o["inlier_rmse_mm"]},
      {"stages", StagesText(stages)},
      {"threads", omp_get_max_threads()},
      {"version", o["open3d_version"]},
      {"method", "open3d " + o["method"].get<std::string>() + ", " + std::to_string(max_iterations) +
                     " iterations max per stage, relative fitness and RMSE 1e-6; its target k-d "
                     "tree is rebuilt inside every call"}};
  return run;
}

}  // namespace
}  // namespace pectus
