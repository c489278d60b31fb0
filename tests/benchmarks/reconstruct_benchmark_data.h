// The clouds of reconstruct_benchmark and the errors of a surface against their truth.
#pragma once

#include <algorithm>
#include <cmath>
#include <map>
#include <optional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "datasets/surface_query.h"
#include "datasets/synth.h"
#include "registration/kdtree.h"
#include "shape/io/mesh_io.h"
#include "shape/io/stanford_conf.h"
#include "shape/sweep_merge.h"
#include "tests/shape/mesh_distance.h"

namespace pectus::bench {

namespace ds = pectus::datasets;

/// A cloud written to a file for every method, and what it is measured against.
struct Dataset {
  std::string name;
  std::string cloud_file;        ///< PLY with pectus' merged, oriented normals
  long long points = 0;
  double spacing_mm = 1.0;       ///< isosurface step given to pectus
  PointCloud cloud;              ///< what was written
  TriangleMesh reference;        ///< bunny: bun_zipper.ply (mm)
  std::optional<ds::ChestSurface> skin;  ///< chests: the exact surface
  std::vector<ds::ScanHole> holes;       ///< chests: the holes
  Points3 truth_samples;         ///< chests: true surface points where a sweep saw it
};

inline Dataset MakeDataset(const std::string& name, const std::string& workdir) {
  Dataset d;
  d.name = name;
  d.cloud_file = workdir + "/" + name + ".ply";
  if (name == "bunny") {
    const std::string dir = std::string(PECTUS_SHARED_DIR) + "/datasets/stanford_bunny/";
    std::vector<ScanPose> poses = ReadStanfordConf(dir + "bun.conf");
    ScaleTranslations(1000.0, &poses);
    ReadOptions ro;
    ro.input_units = LengthUnit::kMetre;
    std::vector<PointCloud> sweeps;
    std::vector<Rigid3> start;
    for (const auto& p : poses) {
      sweeps.push_back(ReadPointCloud(dir + p.file, ro));
      start.push_back(p.T_common_scan);
    }
    d.cloud = MergeSweeps(sweeps, start).merged;
    d.reference = ReadMesh(dir + "reconstruction/bun_zipper.ply", ro);
  } else {
    const double scan_spacing = name == "chest1m" ? 0.295 : 0.93;
    ds::SyntheticSubject subject = ds::MakeSubject(ds::SubjectOptions{}, 7, 0);
    ds::ScanOptions so;
    so.sweeps = 5;
    so.noise_mm = 0.2;
    so.hole_max_mm = 30.0;
    so.spacing_mm = scan_spacing;
    const ds::ScannedSubject scan = ds::ScanSubject(subject, so, 0.0, 7);
    std::vector<PointCloud> sweeps;
    std::vector<Rigid3> truth;
    std::vector<Eigen::Vector3d> samples;
    for (const auto& s : scan.scan.sweeps) {
      sweeps.push_back(s.cloud);
      truth.push_back(s.truth.T_scan_sweep);
      for (Eigen::Index i = 0; i < s.truth.true_points.rows(); i += name == "chest1m" ? 20 : 2) {
        if (!s.truth.outlier[std::size_t(i)]) samples.push_back(s.truth.true_points.row(i).transpose());
      }
    }
    SweepMergeOptions mo;
    mo.refine_poses = false;  // the true merge: this benchmark measures the surface alone
    d.cloud = MergeSweeps(sweeps, truth, mo).merged;
    d.skin = subject.Skin();
    d.holes = scan.scan.holes;
    d.truth_samples.resize(Eigen::Index(samples.size()), 3);
    for (std::size_t i = 0; i < samples.size(); ++i) d.truth_samples.row(Eigen::Index(i)) = samples[i].transpose();
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
  return {{"count", v.size()},         {"mean_mm", sum / n}, {"rms_mm", std::sqrt(sum2 / n)},
          {"p95_mm", v[std::size_t(0.95 * (n - 1))]}, {"max_mm", v.back()}};
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
    for (std::size_t i = 0; i < border.size(); ++i) border_points.row(Eigen::Index(i)) = border[i].transpose();
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
    j["reference_to_surface"] = Stats(std::vector<double>(from_ref.data(), from_ref.data() + from_ref.size()));
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
      if (h.sweep < 0 && (x - h.centre).norm() < 0.5 * h.diameter_mm && data_distance(v) > 2.0) in_hole[std::size_t(v)] = 1;
    }
    if (data_distance(v) <= 1.0 || in_hole[std::size_t(v)]) error(v) = std::abs(ds::SignedDistance(*d.skin, x));
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
  j["truth_to_surface"] = Stats(std::vector<double>(from_truth.data(), from_truth.data() + from_truth.size()));
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
  std::map<std::string, nlohmann::json> pectus;
  for (const auto& r : runs)
    if (r["method"] == "pectus" && !r.contains("error")) pectus[r["dataset"]] = r;
  std::string current;
  for (const auto& r : runs) {
    const std::string name = r["dataset"];
    if (name != current) {
      current = name;
      const bool bunny = name == "bunny";
      out += "\n**" + name + "** (" + std::to_string(r["points"].get<long long>()) + " points)\n\n";
      out += bunny ? "| method | time s | x pectus | peak MB | x pectus | surface->ref mean / p95 mm | "
                     "ref->surface mean / p95 mm | faces |\n|---|---|---|---|---|---|---|---|\n"
                   : "| method | time s | x pectus | peak MB | x pectus | surface->truth RMS / p95 mm | "
                     "truth->surface RMS / p95 mm | in holes max mm | faces |\n|---|---|---|---|---|---|---|---|---|\n";
    }
    if (r.contains("error")) {
      out += "| " + r["method"].get<std::string>() + " | " + r["error"].get<std::string>() + " |\n";
      continue;
    }
    const double t = r["seconds"], m = r["peak_rss_mb"];
    const bool have = pectus.count(name) > 0;
    const double t0 = have ? pectus[name]["seconds"].get<double>() : t;
    const double m0 = have ? pectus[name]["peak_rss_mb"].get<double>() : m;
    out += "| " + r["method"].get<std::string>() + " | " + Fixed(t, 2) + " | " + Fixed(t / t0, 2) + " | " +
           Fixed(m, 0) + " | " + Fixed(m / m0, 2) + " | ";
    const auto& e = r["error_to_truth"];
    auto pair = [&](const char* key, const char* first) {
      return Fixed(e[key][first].get<double>(), 3) + " / " + Fixed(e[key]["p95_mm"].get<double>(), 3);
    };
    if (name == "bunny") {
      out += pair("surface_to_reference", "mean_mm") + " | " + pair("reference_to_surface", "mean_mm") + " | ";
    } else {
      out += pair("surface_to_truth", "rms_mm") + " | " + pair("truth_to_surface", "rms_mm") + " | " +
             (e["in_holes"]["count"].get<long long>() > 0 ? Fixed(e["in_holes"]["max_mm"].get<double>(), 3) : "-") +
             " | ";
    }
    out += std::to_string(r["faces"].get<long long>()) + " |\n";
  }
  return out;
}

}  // namespace pectus::bench
