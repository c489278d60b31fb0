// pectus registration benchmark (issue 4), part "bunny": Stanford bunny sweep pairs (45 and 90 degrees
// apart) from disturbed bun.conf poses: RMS distance to the published placement, how well the scans fit
// at either placement, how well the pair's point-to-plane problem is conditioned, and where the peers
// (Open3D point-to-plane and generalized ICP, PCL IterativeClosestPointWithNormals) converge from the
// published placement itself and from a disturbed start. Included once, by registration_benchmark.cc.
#pragma once

#include <unistd.h>

#include <Eigen/Eigenvalues>
#include <map>

#include "registration/estimate_normals.h"
#include "registration/icp.h"
#include "registration/register_pair.h"
#include "shape/core/error.h"
#include "shape/io/mesh_io.h"
#include "shape/io/stanford_conf.h"
#include "tests/benchmarks/registration_benchmark_peers.h"
#include "tests/support/shared_data.h"

namespace pectus {
namespace {

// The bunny pairs (fixed, moving): neighbouring sweeps 45 degrees apart, then 90 degrees apart (less
// overlap).
const std::vector<std::pair<std::string, std::string>> kBunnyPairs = {
    {"bun000.ply", "bun045.ply"}, {"bun270.ply", "bun315.ply"}, {"bun000.ply", "bun315.ply"},
    {"bun045.ply", "bun090.ply"}, {"bun000.ply", "bun090.ply"}, {"bun315.ply", "bun045.ply"},
    {"bun090.ply", "bun180.ply"}, {"bun180.ply", "bun270.ply"}};

// How well a placement fits the data: the median |point-to-plane distance| (mm) of the moving scan's points
// (every 4th) that have a fixed point within `reach_mm`, and their fraction. The published placement of a
// pair comes from a global alignment of all ten scans, so it need not be the pair's own best fit; this
// says which of two placements the scans themselves prefer.
json PlacementFit(const IcpTarget& target, const Points3& moving, const Rigid3& T, double reach_mm) {
  std::vector<double> r;
  std::int64_t considered = 0;
  for (Eigen::Index i = 0; i < moving.rows(); i += 4) {
    ++considered;
    const Eigen::Vector3d x = T * Eigen::Vector3d(moving.row(i).transpose()) - target.origin();
    std::uint32_t j = 0;
    double d2 = 0.0;
    if (!target.tree().NearestWithin(x, reach_mm, &j, &d2)) continue;
    r.push_back(std::abs((x - target.centred_positions().row(j).transpose()).dot(target.normals().row(j))));
  }
  return {{"median_abs_point_to_plane_mm", Median(r)},
          {"fraction_within_reach", static_cast<double>(r.size()) / static_cast<double>(considered)}};
}

// The point-to-plane normal matrix of the pair at pose T: H = sum J J^T, J = [(p - c) x n / L, n] over the
// moving points (every 2nd) with a fixed point within `gate_mm`, c their centroid, L their RMS distance
// from c (so that the rotation rows are in mm like the translation rows). Reported: its eigenvalues over
// the largest (a near-zero one is a sliding direction), and the pose difference `delta` (T_other T^-1 about
// c, as (L w, t) in mm) resolved along the eigenvectors: a difference that lies along the weakest
// directions is one the data hardly constrain.
json Conditioning(const IcpTarget& target, const Points3& moving, const Rigid3& T, const Rigid3& T_other,
                  double gate_mm) {
  std::vector<Eigen::Vector3d> p, n;
  for (Eigen::Index i = 0; i < moving.rows(); i += 2) {
    const Eigen::Vector3d x = T * Eigen::Vector3d(moving.row(i).transpose()) - target.origin();
    std::uint32_t j = 0;
    double d2 = 0.0;
    if (!target.tree().NearestWithin(x, gate_mm, &j, &d2)) continue;
    p.push_back(x);
    n.push_back(target.normals().row(j).transpose());
  }
  if (p.size() < 6) return {{"error", "fewer than 6 correspondences"}};
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  for (const auto& x : p) c += x;
  c /= static_cast<double>(p.size());
  double l2 = 0.0;
  for (const auto& x : p) l2 += (x - c).squaredNorm();
  const double L = std::sqrt(l2 / static_cast<double>(p.size()));
  Eigen::Matrix<double, 6, 6> H = Eigen::Matrix<double, 6, 6>::Zero();
  for (std::size_t k = 0; k < p.size(); ++k) {
    Eigen::Matrix<double, 6, 1> J;
    J << (p[k] - c).cross(n[k]) / L, n[k];
    H.noalias() += J * J.transpose();
  }
  H /= static_cast<double>(p.size());
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 6, 6>> eig(H);
  // The difference of the poses about c (target's centred frame): x -> D x with D = T_other T^-1.
  const Rigid3 D = T_other * T.inverse();
  const Eigen::Vector3d c_world = c + target.origin();
  const Eigen::AngleAxisd aa(D.linear());
  Eigen::Matrix<double, 6, 1> delta;
  delta << L * aa.angle() * aa.axis(), D * c_world - c_world;
  json values = json::array(), along = json::array();
  for (int k = 0; k < 6; ++k) {
    values.push_back(eig.eigenvalues()(k) / eig.eigenvalues()(5));
    along.push_back(eig.eigenvectors().col(k).dot(delta));
  }
  return {{"correspondences", p.size()},
          {"lever_mm", L},
          {"eigenvalues_over_largest", values},
          {"weakest_direction",
           std::vector<double>(eig.eigenvectors().col(0).data(), eig.eigenvectors().col(0).data() + 6)},
          {"delta_along_eigenvectors_mm", along},
          {"delta",
           "the other placement minus this one about the overlap's centroid, (L w, t) in mm, "
           "resolved along the eigenvectors, weakest first"}};
}

// The loop around the bunny: bun180 <- bun270 composed of the five other pairs' results (bun180 <- bun090 <-
// bun045 <- bun000 <- bun315 <- bun270), against the direct pair's result and the published placement (RMS
// over bun270's points, mm). A pair whose own optimum disagrees with the loop shows here.
json BunnyLoop(const std::map<std::string, Rigid3>& found, const std::map<std::string, Rigid3>& published,
               const Points3& bun270) {
  auto chain = [](const std::map<std::string, Rigid3>& T) {
    return Rigid3(T.at("bun090<-bun180").inverse() * T.at("bun045<-bun090").inverse() *
                  T.at("bun000<-bun045").inverse() * T.at("bun000<-bun315") *
                  T.at("bun270<-bun315").inverse());
  };
  auto rms = [&](const Rigid3& a, const Rigid3& b) {
    return RmsDisplacement(bun270, Similarity3::FromRigid(a), Similarity3::FromRigid(b));
  };
  const Rigid3 loop = chain(found), direct = found.at("bun180<-bun270"),
               truth = published.at("bun180<-bun270");
  return {{"pair", "bun180 <- bun270"},
          {"chain", "bun180 <- bun090 <- bun045 <- bun000 <- bun315 <- bun270 (pectus, seed 1 of each pair)"},
          {"chain_to_published_mm", rms(loop, truth)},
          {"direct_to_published_mm", rms(direct, truth)},
          {"chain_to_direct_mm", rms(loop, direct)}};
}

json Bunny(int seeds, bool peers, json* loop) {
  const fs::path dir = testing_support::BunnyDirectory();
  ReadOptions metres;
  metres.input_units = LengthUnit::kMetre;
  metres.warn_units = false;
  std::vector<ScanPose> poses = ReadStanfordConf(dir / "bun.conf");
  ScaleTranslations(1000.0, &poses);
  auto pose = [&](const std::string& file) {
    for (const ScanPose& p : poses)
      if (p.file == file) return p.T_common_scan;
    ThrowBadInput((dir / "bun.conf").string(), "no pose for " + file);
  };
  const fs::path scratch = fs::temp_directory_path() / ("pectus_reg_bunny_" + std::to_string(::getpid()));
  json out = json::array();
  std::map<std::string, Rigid3> found_by_pair, published_by_pair;
  Points3 bun270;
  for (const auto& [fixed_name, moving_name] : kBunnyPairs) {
    const PointCloud fixed = ReadPointCloud(dir / fixed_name, metres);
    const PointCloud moving = ReadPointCloud(dir / moving_name, metres);
    const Rigid3 published = pose(fixed_name).inverse() * pose(moving_name);
    const Eigen::Vector3d centre = published * Eigen::Vector3d(moving.positions.colwise().mean().transpose());
    auto rms_to_published = [&](const Rigid3& T) {
      return RmsDisplacement(moving.positions, Similarity3::FromRigid(T), Similarity3::FromRigid(published));
    };
    std::vector<double> rms, seconds;
    int success = 0;
    Rigid3 found = Rigid3::Identity(), first_start = Rigid3::Identity();
    IcpResult icp;
    for (int s = 1; s <= seeds; ++s) {
      std::mt19937_64 rng(static_cast<std::uint64_t>(s));
      const Rigid3 start = testing::RandomPose(&rng, 5.0, 10.0, centre) * published;
      const auto t0 = Clock::now();
      const PairRegistrationResult r =
          RegisterPair(fixed, moving, nullptr, nullptr, Similarity3::FromRigid(start));
      seconds.push_back(Since(t0));
      success += r.success;
      const Rigid3 T = r.T_target_source.RigidPart();
      rms.push_back(rms_to_published(T));
      if (s == 1) {
        found = T;
        first_start = start;
        icp = *r.icp;
      }
    }
    // From the published placement itself: where does the pair's own optimum lie?
    const PairRegistrationResult at_published =
        RegisterPair(fixed, moving, nullptr, nullptr, Similarity3::FromRigid(published));
    NormalOptions normals;
    normals.k = 12;
    normals.orientation = NormalOrientation::kNone;
    const IcpTarget target(fixed.positions, normals);
    const double gate = icp.levels.back().max_distance_mm;
    json b = {{"fixed", fixed_name},
              {"moving", moving_name},
              {"starts", seeds},
              {"start", "published pose disturbed by 5 deg about the scan's centre and 10 mm"},
              {"success", success},
              {"rms_to_published_mm_median", Median(rms)},
              {"rms_to_published_mm_max", *std::max_element(rms.begin(), rms.end())},
              {"pectus_from_published_rms_to_published_mm",
               rms_to_published(at_published.T_target_source.RigidPart())},
              {"pectus_conditioning", icp.conditioning},
              {"pectus_rotation_sd_deg", icp.rotation_sd_deg},
              {"pectus_translation_sd_mm", icp.translation_sd_mm},
              {"final_gate_mm", gate},
              {"seconds_median", Median(seconds)},
              {"fit_at_published_1mm", PlacementFit(target, moving.positions, published, 1.0)},
              {"fit_at_pectus_1mm", PlacementFit(target, moving.positions, found, 1.0)},
              {"normal_matrix_at_pectus", Conditioning(target, moving.positions, found, published, gate)},
              {"note", "seconds include estimating the fixed scan's normals"}};
    if (peers) {
      // Every peer gets pectus's normals of both scans (k = 12) and the gate of pectus's last level; from
      // the published placement one stage, from the disturbed start (seed 1) three (20, 5 mm, the gate).
      const Points3 ns = EstimateNormals(moving.positions, normals).normals;
      const Points3& nt = target.normals();
      const std::vector<Stage> one = {{gate, 0}}, staged = {{20.0, 0}, {5.0, 0}, {gate, 0}};
      const Points3& xt = fixed.positions;
      const Points3& xs = moving.positions;
      json& q = b["peers_rms_to_published_mm"];
      q["pcl_from_published"] = rms_to_published(RunPcl(xt, nt, xs, ns, published, one, 50, 1).T);
      q["pcl_from_disturbed"] = rms_to_published(RunPcl(xt, nt, xs, ns, first_start, staged, 50, 1).T);
      WriteOpen3dInputs(scratch, xt, nt, xs, ns, published);
      q["open3d_point_to_plane_from_published"] = rms_to_published(RunOpen3d(scratch, one, 50, 1).T);
      q["open3d_generalized_from_published"] =
          rms_to_published(RunOpen3d(scratch, one, 50, 1, "generalized").T);
      WriteOpen3dInputs(scratch, xt, nt, xs, ns, first_start);
      q["open3d_point_to_plane_from_disturbed"] = rms_to_published(RunOpen3d(scratch, staged, 50, 1).T);
      q["open3d_generalized_from_disturbed"] =
          rms_to_published(RunOpen3d(scratch, staged, 50, 1, "generalized").T);
    }
    out.push_back(b);
    const std::string key = fixed_name.substr(0, 6) + "<-" + moving_name.substr(0, 6);
    found_by_pair[key] = found;
    published_by_pair[key] = published;
    if (moving_name == "bun270.ply") bun270 = moving.positions;
    std::cerr << "bunny: " << fixed_name << " <- " << moving_name << "\n";
  }
  std::error_code ec;
  fs::remove_all(scratch, ec);
  *loop = BunnyLoop(found_by_pair, published_by_pair, bun270);
  return out;
}

}  // namespace
}  // namespace pectus
