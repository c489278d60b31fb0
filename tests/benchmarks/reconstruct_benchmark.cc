// Benchmark of `pectus reconstruct` against its peers on the same clouds, in one run: CGAL Poisson, PCL
// Poisson (depth 8) and Open3D screened Poisson (depth 8, scripts/peers/open3d_poisson.py). Each method
// runs in its own child process, so that its peak memory (wait4's ru_maxrss) is its own; the time is the
// surface stage alone (reading and writing files excluded), as each child measures it.
//
// Clouds: the ten Stanford bunny sweeps merged by pectus (362k points, reference bun_zipper.ply), and
// synthetic chests from the virtual scanner (5 sweeps, noise 0.2 mm, holes up to 30 mm, true poses) at
// about 100k and 1M points, whose exact surface is known.
//
// Also the same-family cross-check: on a 1000-point ellipsoid ("crosscheck2000": 2000 points; PCL's dense
// solve grows as the cube), pectus against PCL's MarchingCubesRBF (one global r^3 spline), both ways, mm.
//
//   build/tests/benchmarks/reconstruct_benchmark [--workdir DIR]
//       [--datasets
//       crosscheck,bunny,chest100k,chest100k_4sweeps,chest100k_6sweeps,chest100k_bigholes,chest1m]
//       [--methods pectus,pectus_normals,cgal,pcl,open3d,open3d_normals] [--threads 1,2]
//       [--timeout SECONDS]
// Every method runs once per thread count (default 1 and 2: "one thread each", "two threads each"):
// OMP_NUM_THREADS for pectus and PCL (pcl::Poisson::setThreads follows it), the process pinned to that
// many cores for Open3D (scripts/peers/open3d_poisson.py --threads); CGAL's Poisson is sequential.
// Internal: reconstruct_benchmark --child METHOD IN.ply OUT.ply SPACING_MM
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <thread>

#include "shape/core/error.h"
#include "shape/io/mesh_io.h"
#include "shape/surface/check_mesh.h"
#include "shape/surface/reconstruct_surface.h"
#include "tests/benchmarks/peers/surface_peers.h"
#include "tests/benchmarks/reconstruct_benchmark_data.h"

using namespace pectus;
namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

namespace {

double Since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

// CPU time of this process, all threads (s).
double CpuSeconds() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return double(u.ru_utime.tv_sec + u.ru_stime.tv_sec) +
         1e-6 * double(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

// One method on one cloud, in this (child) process; prints one JSON line.
int RunChild(const std::string& method, const std::string& in, const std::string& out, double spacing) {
  const PointCloud cloud = ReadPointCloud(in);
  nlohmann::json j{{"method", method}};
  TriangleMesh mesh;
  const auto t0 = Clock::now();
  const double c0 = CpuSeconds();
  if (method == "pectus" || method == "pectus_normals") {
    ReconstructOptions o;
    o.spacing_mm = spacing;
    o.fill_holes_mm = 30.0;
    o.check = false;
    o.recompute_normals = method == "pectus_normals";
    ReconstructResult r = ReconstructSurface(cloud, o, in);
    j["seconds"] = Since(t0);
    j["surface_cpu_s"] = CpuSeconds() - c0;
    for (const auto& [stage, s] : r.timings_s.stages()) j["stages"][stage] = s;
    j["fitting_accuracy_mm"] = r.accuracy.fitting_accuracy_mm;
    j["scales_mm"] = {{"point_spacing", r.point_spacing_mm},
                      {"noise", r.noise_mm},
                      {"centre_spacing", r.centre_spacing_mm},
                      {"working_points", r.working_points}};
    mesh = std::move(r.mesh);
    const MeshCheck check = CheckMesh(mesh);
    j["check"] = {{"manifold", check.manifold},
                  {"self_intersecting", check.self_intersecting},
                  {"closed", check.closed},
                  {"components", check.components},
                  {"seconds", check.timings_s.Total()}};
  } else if (method == "pcl") {
    mesh = PclPoissonSurface(cloud, 8);
    j["seconds"] = Since(t0);
    j["surface_cpu_s"] = CpuSeconds() - c0;
  } else if (method == "cgal") {
    mesh = CgalPoissonSurface(cloud);
    j["seconds"] = Since(t0);
    j["surface_cpu_s"] = CpuSeconds() - c0;
  } else {
    std::fprintf(stderr, "unknown method %s\n", method.c_str());
    return 2;
  }
  j["vertices"] = mesh.num_vertices();
  j["faces"] = mesh.num_faces();
  WriteMesh(out, mesh);
  std::printf("%s\n", j.dump().c_str());
  return 0;
}

// Runs argv as a child with a timeout and OMP_NUM_THREADS=threads; its stdout (last line, JSON), wall
// time and peak memory.
nlohmann::json Spawn(const std::vector<std::string>& args, int threads, double timeout_s) {
  int pipe_fd[2];
  if (pipe(pipe_fd) != 0) return {{"error", "pipe"}};
  const auto t0 = Clock::now();
  const pid_t pid = fork();
  if (pid == 0) {
    dup2(pipe_fd[1], 1);
    close(pipe_fd[0]);
    setenv("OMP_NUM_THREADS", std::to_string(threads).c_str(), 1);
    std::vector<char*> argv;
    for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    execv(argv[0], argv.data());
    _exit(127);
  }
  close(pipe_fd[1]);
  std::string output;
  int status = 0;
  rusage usage{};
  bool timed_out = false;
  char buffer[4096];
  while (true) {
    const pid_t done = wait4(pid, &status, WNOHANG, &usage);
    if (done == pid) break;
    if (Since(t0) > timeout_s) {
      kill(pid, SIGKILL);
      wait4(pid, &status, 0, &usage);
      timed_out = true;
      break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  ssize_t got;
  while ((got = read(pipe_fd[0], buffer, sizeof buffer)) > 0) output.append(buffer, std::size_t(got));
  close(pipe_fd[0]);
  nlohmann::json j;
  std::istringstream lines(output);
  std::string line, last;
  while (std::getline(lines, line))
    if (!line.empty() && line[0] == '{') last = line;
  if (!last.empty()) j = nlohmann::json::parse(last);
  j["wall_s"] = Since(t0);
  j["cpu_s"] = double(usage.ru_utime.tv_sec + usage.ru_stime.tv_sec) +
               1e-6 * double(usage.ru_utime.tv_usec + usage.ru_stime.tv_usec);
  j["peak_rss_mb"] = double(usage.ru_maxrss) / 1024.0;
  if (timed_out) j["error"] = "timeout after " + std::to_string(int(timeout_s)) + " s";
  if (!timed_out && (!WIFEXITED(status) || WEXITSTATUS(status) != 0))
    j["error"] = "exit status " + std::to_string(status);
  return j;
}

std::vector<std::string> Split(const std::string& s) {
  std::vector<std::string> out;
  std::stringstream in(s);
  std::string item;
  while (std::getline(in, item, ',')) out.push_back(item);
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc == 6 && std::string(argv[1]) == "--child")
    return RunChild(argv[2], argv[3], argv[4], std::atof(argv[5]));
  std::string workdir = "/tmp/pectus_reconstruct_benchmark";
  std::vector<std::string> datasets = {
      "crosscheck",         "bunny",  "chest100k", "chest100k_4sweeps", "chest100k_6sweeps",
      "chest100k_bigholes", "chest1m"};
  std::vector<std::string> methods = {"pectus", "pectus_normals", "cgal", "pcl", "open3d", "open3d_normals"};
  std::vector<std::string> threads = {"1", "2"};
  double timeout = 900.0;
  for (int a = 1; a + 1 < argc; a += 2) {
    const std::string key = argv[a], value = argv[a + 1];
    if (key == "--workdir") workdir = value;
    if (key == "--datasets") datasets = Split(value);
    if (key == "--methods") methods = Split(value);
    if (key == "--threads") threads = Split(value);
    if (key == "--timeout") timeout = std::atof(value.c_str());
  }
  if (std::find(datasets.begin(), datasets.end(), "bunny") != datasets.end() &&
      !testing_support::HaveSharedFile("reconstruct_benchmark", testing_support::kBunnyConf)) {
    return 3;
  }
  fs::create_directories(workdir);
  const std::string self = fs::read_symlink("/proc/self/exe").string();
  const std::string script = std::string(PECTUS_SOURCE_DIR) + "/scripts/peers/open3d_poisson.py";
  std::printf("machine: %u threads, %s; load at start: %s\n", std::thread::hardware_concurrency(),
              bench::CpuModel().c_str(), bench::LoadAverage().c_str());
  nlohmann::json all = nlohmann::json::array();
  std::string crosscheck;
  for (const std::string& name : datasets) {
    if (name.rfind("crosscheck", 0) == 0) {  // "crosscheck" (1000 points) or "crosscheckN" (N points)
      crosscheck =
          bench::CrossCheckMarchingCubesRbf(name.size() > 10 ? std::stoi(name.substr(10)) : 1000).dump();
      std::printf("%s\n", crosscheck.c_str());
      std::fflush(stdout);
      continue;
    }
    const auto t0 = Clock::now();
    const bench::Dataset data = bench::MakeDataset(name, workdir);
    std::string holes;
    for (const auto& h : data.holes) {
      if (h.sweep < 0) holes += (holes.empty() ? "" : ", ") + bench::Fixed(h.diameter_mm, 1) + " mm";
    }
    std::printf("%s: %lld points (prepared in %.1f s)%s%s\n", name.c_str(), (long long)data.points, Since(t0),
                holes.empty() ? "" : "; holes missing from every sweep: ", holes.c_str());
    std::fflush(stdout);
    for (const std::string& thread_text : threads)
      for (const std::string& method : methods) {
        const int thread_count = std::max(1, std::atoi(thread_text.c_str()));
        if (method == "pectus_normals" && name != "bunny") continue;  // chests: normals come with the merge
        if (method == "open3d_normals" && name != "bunny") continue;
        const bool variant = name.find('_') != std::string::npos;  // 4 or 6 sweeps, big holes: pectus alone
        if (variant && method != "pectus") continue;
        const std::string out = workdir + "/" + name + "_" + method + ".ply";
        std::vector<std::string> args;
        if (method.rfind("open3d", 0) == 0) {
          args = {"/usr/bin/python3", script, data.cloud_file, out, "--depth", "8", "--threads", thread_text};
          if (method == "open3d_normals") args.push_back("--estimate-normals");
        } else {
          args = {self, "--child", method, data.cloud_file, out, std::to_string(data.spacing_mm)};
        }
        nlohmann::json r = Spawn(args, thread_count, timeout);
        r["dataset"] = name;
        r["threads"] = thread_count;
        r["method"] = method;
        r["points"] = data.points;
        if (r.contains("total_s")) r["seconds"] = r["total_s"];
        if (!r.contains("error") && fs::exists(out))
          r["error_to_truth"] = bench::Evaluate(data, ReadMesh(out));
        std::printf("%s\n", r.dump().c_str());
        std::fflush(stdout);
        all.push_back(r);
      }
  }
  std::printf("\n%s", bench::MarkdownTable(all).c_str());
  if (!crosscheck.empty()) std::printf("\nMarchingCubesRBF cross-check: %s\n", crosscheck.c_str());
  std::printf("load at end: %s\n", bench::LoadAverage().c_str());
  return 0;
}
