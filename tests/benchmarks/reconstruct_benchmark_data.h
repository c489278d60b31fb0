// The clouds of reconstruct_benchmark and the errors of a surface against their truth.
#pragma once

#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "datasets/surface_query.h"
#include "datasets/synth.h"
#include "registration/kdtree.h"
#include "shape/io/mesh_io.h"
#include "shape/io/stanford_conf.h"
#include "shape/surface/merge_sweeps.h"
#include "shape/surface/reconstruct_surface.h"
#include "tests/benchmarks/peers/surface_peers.h"
#include "tests/shape/mesh_distance.h"
#include "tests/support/bunny_data.h"
#include "tests/support/synthetic_clouds.h"

namespace pectus::bench {

namespace ds = pectus::datasets;

/// A cloud written to a file for every method, and what it is measured against.
struct Dataset {
  std::string name;
  std::string cloud_file;  ///< PLY with pectus' merged, oriented normals
  long long points = 0;
  double spacing_mm = 1.0;               ///< isosurface step given to pectus
  PointCloud cloud;                      ///< what was written
  TriangleMesh reference;                ///< bunny: bun_zipper.ply (mm)
  std::optional<ds::ChestSurface> skin;  ///< chests: the exact surface
  std::vector<ds::ScanHole> holes;       ///< chests: the holes
  Points3 truth_samples;                 ///< chests: true surface points where a sweep saw it
};

inline Dataset MakeDataset(const std::string& name, const std::string& workdir) {
  Dataset d;
  d.name = name;
  d.cloud_file = workdir + "/" + name + ".ply";
  if (name == "bunny") {
    const testing_support::BunnySweeps bunny = testing_support::ReadBunnySweeps();
    d.cloud = MergeSweeps(bunny.sweeps, bunny.placements).merged;
    ReadOptions ro;
    ro.input_units = LengthUnit::kMetre;
    d.reference = ReadMesh(testing_support::BunnyDirectory() + "reconstruction/bun_zipper.ply", ro);
  } else {
    // "chest100k" and "chest1m" (5 sweeps); "chest100k_4sweeps", "chest100k_6sweeps": the same subject
    // scanned with 4 or 6 strips at the same line spacing; "chest100k_bigholes": with three large holes.
    const bool million = name.rfind("chest1m", 0) == 0;
    const double scan_spacing = million ? 0.295 : 0.93;
    const auto sweeps_at = name.find("sweeps");
    ds::SyntheticSubject subject = ds::MakeSubject(ds::SubjectOptions{}, 7, 0);
    ds::ScanOptions so;
    so.sweeps = sweeps_at == std::string::npos ? 5 : std::atoi(name.substr(sweeps_at - 1, 1).c_str());
    so.noise_mm = 0.2;
    so.hole_max_mm = 30.0;
    if (name.find("bigholes") != std::string::npos) {  // three holes of 24-30 mm missing from every sweep
      so.subject_holes = 3;
      so.hole_min_mm = 24.0;
    }
    so.spacing_mm = scan_spacing;
    const ds::ScannedSubject scan = ds::ScanSubject(subject, so, 0.0, 7);
    std::vector<PointCloud> sweeps;
    std::vector<Rigid3> truth;
    std::vector<Eigen::Vector3d> samples;
    for (const auto& s : scan.scan.sweeps) {
      sweeps.push_back(s.cloud);
      truth.push_back(s.truth.T_scan_sweep);
      for (Eigen::Index i = 0; i < s.truth.true_points.rows(); i += million ? 20 : 2) {
        if (!s.truth.outlier[std::size_t(i)]) samples.push_back(s.truth.true_points.row(i).transpose());
      }
    }
    SweepMergeOptions mo;
    mo.refine_poses = false;  // the true merge: this benchmark measures the surface alone
    d.cloud = MergeSweeps(sweeps, truth, mo).merged;
    d.skin = subject.Skin();
    d.holes = scan.scan.holes;
    d.truth_samples.resize(Eigen::Index(samples.size()), 3);
    for (std::size_t i = 0; i < samples.size(); ++i)
      d.truth_samples.row(Eigen::Index(i)) = samples[i].transpose();
  }
  d.cloud.scalars.clear();
  d.points = d.cloud.size();
  WritePointCloud(d.cloud_file, d.cloud);
  return d;
}

inline nlohmann::json Stats(std::vector<double> v) {
  if (v.empty()) return {{"count", 0}};
  std::sort(v.begin(), v.end());
  double sum = 0, sum2 = 0;
  for (double x : v) {
    sum += x;
    sum2 += x * x;
  }
  const double n = double(v.size());
  return {{"count", v.size()},
          {"mean_mm", sum / n},
          {"rms_mm", std::sqrt(sum2 / n)},
          {"p95_mm", v[std::size_t(0.95 * (n - 1))]},
          {"max_mm", v.back()}};
}

/// Errors of a surface against the dataset's truth, both directions.
inline nlohmann::json Evaluate(const Dataset& d, const TriangleMesh& mesh) {
  nlohmann::json j;
  if (mesh.num_faces() == 0) return {{"error", "no triangles"}};
  if (d.name == "bunny") {
    // Surface -> reference where the reference has surface: points whose closest reference point lies on
    // its border (the open base) are left out. Reference -> surface: every reference vertex.
    std::map<std::pair<int, int>, int> edges;
    for (Eigen::Index f = 0; f < d.reference.num_faces(); ++f)
      for (int c = 0; c < 3; ++c) {
        const int a = d.reference.faces(f, c), b = d.reference.faces(f, (c + 1) % 3);
        ++edges[{std::min(a, b), std::max(a, b)}];
      }
    std::vector<Eigen::Vector3d> border;
    for (const auto& [e, count] : edges) {
      if (count != 1) continue;
      const Eigen::Vector3d a = d.reference.vertices.positions.row(e.first).transpose();
      const Eigen::Vector3d b = d.reference.vertices.positions.row(e.second).transpose();
      const int steps = int((a - b).norm() / 0.05) + 1;
      for (int k = 0; k <= steps; ++k) border.push_back(a + (b - a) * double(k) / steps);
    }
    Points3 border_points(Eigen::Index(border.size()), 3);
    for (std::size_t i = 0; i < border.size(); ++i)
      border_points.row(Eigen::Index(i)) = border[i].transpose();
    const KdTree3 border_tree(border_points);
    Points3 closest;
    const Eigen::VectorXd to_ref = testing::DistancesToMesh(mesh.vertices.positions, d.reference, &closest);
    std::vector<double> kept;
    for (Eigen::Index i = 0; i < to_ref.size(); ++i) {
      std::uint32_t k;
      double d2;
      if (!border_tree.NearestWithin(closest.row(i).transpose(), 0.06, &k, &d2)) kept.push_back(to_ref(i));
    }
    j["surface_to_reference"] = Stats(kept);
    j["surface_to_reference"]["left_out"] = to_ref.size() - Eigen::Index(kept.size());
    const Eigen::VectorXd from_ref = testing::DistancesToMesh(d.reference.vertices.positions, mesh);
    j["reference_to_surface"] =
        Stats(std::vector<double>(from_ref.data(), from_ref.data() + from_ref.size()));
    return j;
  }
  // Chests: surface -> truth at vertices within 1 mm of the data; inside holes of every sweep at vertices
  // more than 2 mm from the data; truth -> surface from true points that a sweep saw.
  const KdTree3 data(d.cloud.positions);
  const Eigen::Index n = mesh.num_vertices();
  Eigen::VectorXd error = Eigen::VectorXd::Zero(n), data_distance(n);
  std::vector<char> in_hole(std::size_t(n), 0);
#pragma omp parallel for schedule(dynamic, 256)
  for (Eigen::Index v = 0; v < n; ++v) {
    const Eigen::Vector3d x = mesh.vertices.positions.row(v).transpose();
    std::uint32_t k;
    double d2;
    data.Nearest(x, &k, &d2);
    data_distance(v) = std::sqrt(d2);
    for (const auto& h : d.holes) {
      if (h.sweep < 0 && (x - h.centre).norm() < 0.5 * h.diameter_mm && data_distance(v) > 2.0)
        in_hole[std::size_t(v)] = 1;
    }
    if (data_distance(v) <= 1.0 || in_hole[std::size_t(v)])
      error(v) = std::abs(ds::SignedDistance(*d.skin, x));
  }
  std::vector<double> where_data, in_holes;
  for (Eigen::Index v = 0; v < n; ++v) {
    if (in_hole[std::size_t(v)]) {
      in_holes.push_back(error(v));
    } else if (data_distance(v) <= 1.0) {
      where_data.push_back(error(v));
    }
  }
  j["surface_to_truth"] = Stats(where_data);
  j["in_holes"] = Stats(in_holes);
  const Eigen::VectorXd from_truth = testing::DistancesToMesh(d.truth_samples, mesh);
  j["truth_to_surface"] =
      Stats(std::vector<double>(from_truth.data(), from_truth.data() + from_truth.size()));
  return j;
}

/// The machine, for the record.
inline std::string CpuModel() {
  std::ifstream in("/proc/cpuinfo");
  std::string line;
  while (std::getline(in, line))
    if (line.rfind("model name", 0) == 0) return line.substr(line.find(':') + 2);
  return "unknown CPU";
}
inline std::string LoadAverage() {
  std::ifstream in("/proc/loadavg");
  std::string a, b, c;
  in >> a >> b >> c;
  return a + " " + b + " " + c;
}

/// Same-family cross-check: an ellipsoid (semi-axes 30, 22, 16 mm) sampled at n points with exact
/// normals, reconstructed by pectus (interpolating: smoothing 0, centres at about the point spacing) and
/// by PCL's MarchingCubesRBF (one global r^3 spline, dense solve); distances between the two surfaces,
/// both ways, where PCL's surface is within 4 mm of the data.
inline nlohmann::json CrossCheckMarchingCubesRbf(int n) {
  const PointCloud cloud = testing_support::EllipsoidCloud(n);
  ReconstructOptions o;
  o.spacing_mm = 0.75;
  o.smoothing = 0.0;
  o.detail_mm = 2.0;
  auto t0 = std::chrono::steady_clock::now();
  const ReconstructResult ours = ReconstructSurface(cloud, o, "ellipsoid");
  const double ours_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  t0 = std::chrono::steady_clock::now();
  const TriangleMesh pcl = PclMarchingCubesRbf(cloud, 64, 1.0);
  const double pcl_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const KdTree3 data(cloud.positions);
  std::vector<Eigen::Vector3d> near;
  for (Eigen::Index v = 0; v < pcl.num_vertices(); ++v) {
    std::uint32_t k;
    double d2;
    if (data.NearestWithin(pcl.vertices.positions.row(v).transpose(), 4.0, &k, &d2))
      near.push_back(pcl.vertices.positions.row(v).transpose());
  }
  Points3 pcl_near(Eigen::Index(near.size()), 3);
  for (std::size_t i = 0; i < near.size(); ++i) pcl_near.row(Eigen::Index(i)) = near[i].transpose();
  const Eigen::VectorXd a = testing::DistancesToMesh(ours.mesh.vertices.positions, pcl);
  const Eigen::VectorXd b = testing::DistancesToMesh(pcl_near, ours.mesh);
  nlohmann::json j{{"points", n},
                   {"pectus_s", ours_s},
                   {"pcl_marching_cubes_rbf_s", pcl_s},
                   {"pectus_to_pcl", Stats(std::vector<double>(a.data(), a.data() + a.size()))},
                   {"pcl_to_pectus", Stats(std::vector<double>(b.data(), b.data() + b.size()))},
                   {"pcl_vertices_near_data", near.size()},
                   {"pcl_vertices", pcl.num_vertices()}};
  j["max_apart_mm"] = std::max(a.maxCoeff(), b.maxCoeff());
  return j;
}

inline std::string Fixed(double x, int digits) {
  char text[64];
  std::snprintf(text, sizeof text, "%.*f", digits, x);
  return text;
}

/// One table per dataset: time, memory and error of each method, and their ratios to pectus.
inline std::string MarkdownTable(const nlohmann::json& runs) {
  std::string out;
  // Runs are grouped by dataset and thread count; ratios are to pectus in the same group.
  auto group = [](const nlohmann::json& r) {
    const int t = r.value("threads", 0);
    return r["dataset"].get<std::string>() +
           (t > 0 ? ", " + std::to_string(t) + (t == 1 ? " thread each" : " threads each") : "");
  };
  std::map<std::string, nlohmann::json> pectus;
  for (const auto& r : runs)
    if (r["method"] == "pectus" && !r.contains("error")) pectus[group(r)] = r;
  // CPU time of the surface stage (all threads) where the method measured it, else of its whole process.
  auto cpu = [](const nlohmann::json& r) {
    return r.contains("surface_cpu_s") ? r["surface_cpu_s"].get<double>() : r["cpu_s"].get<double>();
  };
  std::string current;
  for (const auto& r : runs) {
    const std::string name = r["dataset"], group_key = group(r);
    if (group_key != current) {
      current = group_key;
      const bool bunny = name == "bunny";
      out += "\n**" + group_key + "** (" + std::to_string(r["points"].get<long long>()) + " points)\n\n";
      out += bunny ? "| method | time s | x pectus | CPU s | x pectus | peak MB | x pectus | surface->ref "
                     "mean / p95 mm | "
                     "ref->surface mean / p95 mm | faces |\n|---|---|---|---|---|---|---|---|---|---|\n"
                   : "| method | time s | x pectus | CPU s | x pectus | peak MB | x pectus | surface->truth "
                     "RMS / p95 mm | "
                     "truth->surface RMS / p95 mm | in holes max mm | faces "
                     "|\n|---|---|---|---|---|---|---|---|---|---|---|\n";
    }
    if (r.contains("error")) {
      out += "| " + r["method"].get<std::string>() + " | " + r["error"].get<std::string>() + " |\n";
      continue;
    }
    const double t = r["seconds"], m = r["peak_rss_mb"];
    const bool have = pectus.count(group_key) > 0;
    const double t0 = have ? pectus[group_key]["seconds"].get<double>() : t;
    const double m0 = have ? pectus[group_key]["peak_rss_mb"].get<double>() : m;
    const double cpu0 = have ? cpu(pectus[group_key]) : cpu(r);
    out += "| " + r["method"].get<std::string>() + " | " + Fixed(t, 2) + " | " + Fixed(t / t0, 2) + " | " +
           Fixed(cpu(r), 2) + " | " + Fixed(cpu(r) / cpu0, 2) + " | " + Fixed(m, 0) + " | " +
           Fixed(m / m0, 2) + " | ";
    const auto& e = r["error_to_truth"];
    auto pair = [&](const char* key, const char* first) {
      return Fixed(e[key][first].get<double>(), 3) + " / " + Fixed(e[key]["p95_mm"].get<double>(), 3);
    };
    if (name == "bunny") {
      out +=
          pair("surface_to_reference", "mean_mm") + " | " + pair("reference_to_surface", "mean_mm") + " | ";
    } else {
      out += pair("surface_to_truth", "rms_mm") + " | " + pair("truth_to_surface", "rms_mm") + " | " +
             (e["in_holes"]["count"].get<long long>() > 0 ? Fixed(e["in_holes"]["max_mm"].get<double>(), 3)
                                                          : "-") +
             " | ";
    }
    out += std::to_string(r["faces"].get<long long>());
    if (r.contains("check")) {
      const auto& c = r["check"];
      out += c["manifold"].get<bool>() && !c["self_intersecting"].get<bool>()
                 ? std::string(", CGAL: manifold, no self-intersections") +
                       (c["closed"].get<bool>() ? ", closed" : ", open")
                 : std::string(", CGAL CHECK FAILED");
    }
    out += " |\n";
  }
  return out;
}

}  // namespace pectus::bench
