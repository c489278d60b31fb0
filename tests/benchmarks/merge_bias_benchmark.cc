// Why MergeSweeps moves sweeps given their exact poses (issue 13): a probe of the per-pair constraint of
// AdjustPosesToTracker evaluated AT THE TRUE POSES, on synthetic chest sweeps with exact truth.
//
// Per linked pair, the point-to-plane residuals r = n_i . (p - q) of its correspondences (both
// directions, the merge's finest gate) are reduced as AdjustPosesToTracker does (Cauchy weights, the
// residuals' MAD scale) to H = sum w J J^T, g = sum w r J and the normals' noise information B; along each
// generalised eigen-direction u (H u = lambda B u) the gradient's z-score u.g / sqrt(lambda), which is
// N(0, 1) if the residuals are independent, zero-mean and of the scale s. Then:
//   - the residual split into three exact parts: "curvature" n_true(q) . (p_true - q_true) (the surface's
//     bend across the tangential offset of the pair, kappa d^2 / 2), "normal" (n_i - n_true) . (p_true -
//     q_true) (the estimated normal's error times that offset), "noise" n_i . (noise_p - noise_q) (range
//     noise); each part's z-score (they add up to the whole);
//   - the same z-score from correspondences near a border of either sweep (edge, ragged edge, hole rim:
//     within --border-mm of a border point) and from the interior;
//   - the gradient's actual variance against the model's lambda: the sandwich u' (sum_m G_m G_m^T) u /
//     lambda over single correspondences ("sandwich_point", G_m = w (r - J.x) J at the pair's own
//     least-squares x) and over cubes of --block-mm ("sandwich_block": residuals correlated within a
//     block count together), and the correlation of residuals against the distance between their points;
//   - the z-score of other residual definitions, each with its own scale and its variance from the
//     squared gradient terms (z) or blocks (zb): the plane through q's neighbourhood centroid
//     ("centroid"), q's normal fitted without q ("loo"), the exact normal ("exact_normal"), the derivative
//     along the source sweep's normal at p ("iv_raw"; fitted without p: "iv_loo"; with both ends at their
//     neighbourhood centroids: "iv_centroids", and with the target's normal: "both_centroids").
// Per pair and direction the JSON also gives the step the pair would take from the truth (move_mm, RMS
// displacement of its correspondences' points) and its predicted standard deviation (sd_mm).
// JSON on stdout; per eigenvalue band (of lambda), the RMS and median of every figure on stderr.
//
//   build/tests/benchmarks/merge_bias_benchmark [--overlap 0.15,0.2] [--sampling grid,random] [--sweeps 5]
//       [--seeds 3] [--seed 1] [--pattern horizontal] [--spacing 1.5] [--block-mm 10] [--border-mm 5]
#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

#include "datasets/synth.h"
#include "registration/kdtree.h"
#include "registration/robust_loss.h"
#include "shape/surface/merge_sweeps.h"
#include "shape/surface/sweep_graph.h"
#include "shape/surface/sweep_surface.h"
#include "tests/benchmarks/merge_bias_benchmark_probe.h"

using namespace pectus;
namespace ds = pectus::datasets;
using json = nlohmann::json;
using Vector6 = Eigen::Matrix<double, 6, 1>;
using Matrix6 = Eigen::Matrix<double, 6, 6>;

using namespace merge_bias;

int main(int argc, char** argv) {
  const Flags f = Parse(argc, argv);
  json out = json::array();
  Accumulator acc;
  const std::vector<std::string> parts = {"full", "curvature", "normal", "noise", "border", "interior"};
  for (double overlap : f.overlap) {
    for (const std::string& sampling : f.sampling) {
      for (int k = 0; k < f.seeds; ++k) {
        const std::uint64_t seed = std::uint64_t(f.seed + k);
        ds::ScanOptions o;
        o.pattern = ds::ParseSweepPattern(f.pattern);
        o.sampling = ds::ParseScanSampling(sampling);
        o.sweeps = f.sweeps;
        o.overlap = overlap;
        o.spacing_mm = f.spacing_mm;
        o.tracker_pivot = ds::TrackerPivot::kLever;
        o.tracker_deg = o.tracker_mm = 0.0;
        const ds::SyntheticSubject subject = ds::MakeSubject(ds::SubjectOptions{}, seed, 0);
        const ds::ScannedSubject scanned = ds::ScanSubject(subject, o, 0.0, ds::CohortScanSeed(seed, 0));
        const ds::ChestSurface skin = subject.Skin();
        const std::size_t n = scanned.scan.sweeps.size();
        std::vector<PointCloud> clouds;
        std::vector<Rigid3> P;
        for (const auto& s : scanned.scan.sweeps) {
          clouds.push_back(s.cloud);
          P.push_back(s.truth.T_scan_sweep);
        }
        const SweepMergeOptions mo;
        std::vector<SweepSurface> S;
        for (std::size_t s = 0; s < n; ++s) S.push_back(PrepareSweep(clouds[s], mo.surface, "s"));
        OrientSweeps(P, mo.StartingRadiusMm(), 0, &S);
        double spacing = 0;
        for (const auto& w : S) spacing += w.spacing_mm / double(n);
        const double gate = 3.0 * spacing;
        const auto links = FindSweepLinks(S, P, mo.StartingRadiusMm(), mo.min_overlap_fraction);
        const auto corr = AllCorrespondences(S, P, links, mo.global_points_per_pair, gate);
        // Rows of p and q: the clouds' own points (exact matches).
        std::vector<Points3> world(n);
        std::vector<std::unique_ptr<KdTree3>> trees;
        std::vector<std::vector<double>> border(n);
        for (std::size_t s = 0; s < n; ++s) {
          trees.push_back(std::make_unique<KdTree3>(clouds[s].positions));
          world[s] =
              (clouds[s].positions * P[s].linear().transpose()).rowwise() + P[s].translation().transpose();
          border[s] = BorderDistance(world[s], S[s], 100.0);
        }
        auto row = [&](std::size_t s, const Eigen::Vector3d& x) {
          std::uint32_t r = 0;
          double d2 = 0;
          trees[s]->Nearest(x, &r, &d2);
          return r;
        };
        std::vector<Probe> probes;
        for (const auto& c : corr) {
          Probe pr;
          pr.i = c.i;
          pr.j = c.j;
          const std::uint32_t rp = row(c.j, c.p), rq = row(c.i, c.q);
          const auto& tj = scanned.scan.sweeps[c.j].truth;
          const auto& ti = scanned.scan.sweeps[c.i].truth;
          pr.p = P[c.j] * c.p;
          pr.q = P[c.i] * c.q;
          pr.n = P[c.i].linear() * c.n;
          pr.p_true = tj.true_points.row(rp).transpose();
          pr.q_true = ti.true_points.row(rq).transpose();
          pr.n_true = skin.Evaluate(ti.u(rq), ti.v(rq)).normal;
          if (pr.n_true.dot(pr.n) < 0) pr.n_true = -pr.n_true;
          pr.near_border = border[c.i][rq] < f.border_mm || border[c.j][rp] < f.border_mm;
          {
            std::uint32_t nn[17];
            double d2[17];
            const int found = trees[c.i]->Knn(c.q, 17, nn, d2);
            Eigen::Vector3d normal, centroid;
            Pca(clouds[c.i].positions, nn, std::min(found, 16), &normal, &centroid);
            pr.centroid = P[c.i] * centroid;
            // Leave q out: the 16 nearest others.
            std::uint32_t others[16];
            int m = 0;
            for (int t = 0; t < found && m < 16; ++t)
              if (nn[t] != rq) others[m++] = nn[t];
            Pca(clouds[c.i].positions, others, m, &normal, &centroid);
            pr.n_loo = P[c.i].linear() * normal;
            if (pr.n_loo.dot(pr.n) < 0) pr.n_loo = -pr.n_loo;
            const int found_p = trees[c.j]->Knn(c.p, 17, nn, d2);
            m = 0;
            for (int t = 0; t < found_p && m < 16; ++t)
              if (nn[t] != rp) others[m++] = nn[t];
            Pca(clouds[c.j].positions, others, m, &normal, &centroid);
            pr.m_loo = P[c.j].linear() * normal;
            if (pr.m_loo.dot(pr.n) < 0) pr.m_loo = -pr.m_loo;
            Pca(clouds[c.j].positions, nn, std::min(found_p, 16), &normal, &centroid);
            pr.p_centroid = P[c.j] * centroid;
            pr.m = P[c.j].linear() * S[c.j].normals.row(rp).transpose();
            if (pr.m.dot(pr.n) < 0) pr.m = -pr.m;
          }
          probes.push_back(pr);
        }
        // Group by pair, as AdjustPosesToTracker does.
        std::map<std::pair<std::size_t, std::size_t>, std::vector<std::size_t>> groups;
        for (std::size_t a = 0; a < probes.size(); ++a)
          groups[{std::min(probes[a].i, probes[a].j), std::max(probes[a].i, probes[a].j)}].push_back(a);
        std::vector<double> abs_r;
        for (const auto& pr : probes) abs_r.push_back(std::abs(pr.n.dot(pr.p - pr.q)));
        const double scale = std::max(0.02, MadScale(&abs_r));
        const double c_loss = RobustTuningConstant(RobustLoss::kCauchy) * scale;
        for (const auto& [key, members] : groups) {
          Eigen::Vector3d centre = Eigen::Vector3d::Zero();
          for (std::size_t a : members) centre += probes[a].p / double(members.size());
          Matrix6 H = Matrix6::Zero(), B = Matrix6::Zero();
          std::map<std::string, Vector6> g;
          for (const auto& name : parts) g[name] = Vector6::Zero();
          std::vector<Vector6> J(members.size());
          std::vector<double> w(members.size()), r(members.size());
          std::vector<std::array<double, 3>> split(members.size());
          for (std::size_t m = 0; m < members.size(); ++m) {
            const Probe& pr = probes[members[m]];
            const Eigen::Vector3d arm = pr.p - centre;
            const double sign = pr.j > pr.i ? 1.0 : -1.0;
            J[m] << arm.cross(pr.n), pr.n;
            J[m] *= sign;
            r[m] = pr.n.dot(pr.p - pr.q);
            const double curvature = pr.n_true.dot(pr.p_true - pr.q_true);
            const double normal = (pr.n - pr.n_true).dot(pr.p_true - pr.q_true);
            const double noise = pr.n.dot((pr.p - pr.p_true) - (pr.q - pr.q_true));
            split[m] = {curvature, normal, noise};
            w[m] = RobustWeight(RobustLoss::kCauchy, r[m], c_loss) / (scale * scale);
            H += w[m] * J[m] * J[m].transpose();
            g["full"] += w[m] * r[m] * J[m];
            g["curvature"] += w[m] * curvature * J[m];
            g["normal"] += w[m] * normal * J[m];
            g["noise"] += w[m] * noise * J[m];
            g[pr.near_border ? "border" : "interior"] += w[m] * r[m] * J[m];
            const double e2 = S[pr.i].normal_variance;
            const Eigen::Vector3d t1 = pr.n.unitOrthogonal(), t2 = pr.n.cross(t1);
            for (const Eigen::Vector3d& t : {t1, t2}) {
              Vector6 Jt;
              Jt << arm.cross(t), t;
              B += w[m] * e2 * Jt * Jt.transpose();
            }
          }
          const Matrix6 Bs = B + (std::max(B.trace(), H.trace()) * 1e-12 + 1e-300) * Matrix6::Identity();
          Eigen::GeneralizedSelfAdjointEigenSolver<Matrix6> ges(H, Bs);
          // The pair's own least-squares step (at the truth: its error), and the block sandwich.
          const Vector6 x = -H.ldlt().solve(g["full"]);
          std::map<std::tuple<long, long, long>, Vector6> blocks;
          Matrix6 V1 = Matrix6::Zero();
          for (std::size_t m = 0; m < members.size(); ++m) {
            const Probe& pr = probes[members[m]];
            const Vector6 gm = w[m] * (r[m] + J[m].dot(x)) * J[m];
            V1 += gm * gm.transpose();
            const auto b = std::make_tuple(long(std::floor(pr.p.x() / f.block_mm)),
                                           long(std::floor(pr.p.y() / f.block_mm)),
                                           long(std::floor(pr.p.z() / f.block_mm)));
            auto it = blocks.find(b);
            if (it == blocks.end()) it = blocks.emplace(b, Vector6::Zero()).first;
            it->second += gm;
          }
          Matrix6 V = Matrix6::Zero();
          for (const auto& [b, gb] : blocks) V += gb * gb.transpose();
          // Residual correlation against distance (bins of the spacing).
          std::vector<double> bins = {1.0, 2.0, 3.0, 4.0, 6.0, 10.0};  // in spacings
          std::vector<double> cov(bins.size(), 0.0), cnt(bins.size(), 0.0);
          double var = 0;
          for (std::size_t m = 0; m < members.size(); ++m) var += r[m] * r[m];
          var /= double(members.size());
          Points3 pos(Eigen::Index(members.size()), 3);
          for (std::size_t m = 0; m < members.size(); ++m) pos.row(Eigen::Index(m)) = probes[members[m]].p;
          const KdTree3 ptree(pos);
          std::vector<std::pair<std::uint32_t, double>> near;
          for (std::size_t m = 0; m < members.size(); ++m) {
            ptree.Radius(pos.row(Eigen::Index(m)).transpose(), bins.back() * spacing, &near, false);
            for (const auto& [other, d2] : near) {
              if (other == m) continue;
              const double d = std::sqrt(d2) / spacing;
              std::size_t b = 0;
              while (b + 1 < bins.size() && d >= bins[b]) ++b;
              cov[b] += r[m] * r[other];
              cnt[b] += 1;
            }
          }
          // The same for other residual definitions (variant: the residual's two points, its normal and
          // the derivative's normal): z = u.g / sqrt(u' V u) with V the sum of the squared gradient terms
          // (independent residuals, each variant's own scale) and, zb, over blocks (correlated ones).
          for (const std::string variant : {"merge", "centroid", "loo", "exact_normal", "iv_raw",
                                            "iv_centroids", "both_centroids", "iv_loo"}) {
            std::vector<double> rv(members.size()), av(members.size());
            std::vector<Vector6> Jv(members.size());
            for (std::size_t m = 0; m < members.size(); ++m) {
              const Probe& pr = probes[members[m]];
              const Eigen::Vector3d nv = variant == "exact_normal" ? pr.n_true
                                         : variant == "loo"        ? pr.n_loo
                                                                   : pr.n;
              const Eigen::Vector3d nj = variant == "iv_loo"                                  ? pr.m_loo
                                         : (variant == "iv_raw" || variant == "iv_centroids") ? pr.m
                                                                                              : nv;
              const bool centroids = variant == "iv_centroids" || variant == "both_centroids";
              const Eigen::Vector3d anchor = (centroids || variant == "centroid") ? pr.centroid : pr.q;
              const Eigen::Vector3d source = centroids ? pr.p_centroid : pr.p;
              Jv[m] << (pr.p - centre).cross(nj), nj;
              Jv[m] *= pr.j > pr.i ? 1.0 : -1.0;
              rv[m] = nv.dot(source - anchor);
              av[m] = std::abs(rv[m]);
            }
            const double sv = std::max(1e-3, MadScale(&av));
            const double cv = RobustTuningConstant(RobustLoss::kCauchy) * sv;
            Matrix6 Hv = Matrix6::Zero(), Bv = Matrix6::Zero(), Vp = Matrix6::Zero();
            Vector6 gv = Vector6::Zero();
            std::map<std::tuple<long, long, long>, Vector6> vblocks;
            for (std::size_t m = 0; m < members.size(); ++m) {
              const Probe& pr = probes[members[m]];
              const double wv = RobustWeight(RobustLoss::kCauchy, rv[m], cv) / (sv * sv);
              Hv += wv * Jv[m] * Jv[m].transpose();
              const Vector6 gm = wv * rv[m] * Jv[m];
              gv += gm;
              Vp += gm * gm.transpose();
              const auto b = std::make_tuple(long(std::floor(pr.p.x() / f.block_mm)),
                                             long(std::floor(pr.p.y() / f.block_mm)),
                                             long(std::floor(pr.p.z() / f.block_mm)));
              auto it = vblocks.find(b);
              if (it == vblocks.end()) it = vblocks.emplace(b, Vector6::Zero()).first;
              it->second += gm;
              const double e2 = S[pr.i].normal_variance;
              const Eigen::Vector3d nj = Jv[m].tail<3>();
              const Eigen::Vector3d t1 = nj.unitOrthogonal(), t2 = nj.cross(t1);
              for (const Eigen::Vector3d& t : {t1, t2}) {
                Vector6 Jt;
                Jt << (pr.p - centre).cross(t), t;
                Bv += wv * e2 * Jt * Jt.transpose();
              }
            }
            Matrix6 Vb = Matrix6::Zero();
            for (const auto& [b, gb] : vblocks) Vb += gb * gb.transpose();
            const Matrix6 Bvs =
                Bv + (std::max(Bv.trace(), Hv.trace()) * 1e-12 + 1e-300) * Matrix6::Identity();
            Eigen::GeneralizedSelfAdjointEigenSolver<Matrix6> gv_es(Hv, Bvs);
            for (int d = 0; d < 6; ++d) {
              // Bands by the merge's own lambda of the same rank, so that every variant is binned alike.
              const std::string band = Band(ges.eigenvalues()(d));
              const Vector6 u = gv_es.eigenvectors().col(d);
              acc.Add(band + " " + variant + " z", u.dot(gv) / std::sqrt(std::max(u.dot(Vp * u), 1e-300)));
              acc.Add(band + " " + variant + " zb", u.dot(gv) / std::sqrt(std::max(u.dot(Vb * u), 1e-300)));
              acc.Add(band + " " + variant + " Vb/Vp", u.dot(Vb * u) / std::max(u.dot(Vp * u), 1e-300));
            }
          }
          json pair = {{"overlap", overlap}, {"sampling", sampling},    {"seed", seed},     {"i", key.first},
                       {"j", key.second},    {"count", members.size()}, {"scale_mm", scale}};
          json dirs = json::array();
          for (int d = 0; d < 6; ++d) {
            const double lambda = ges.eigenvalues()(d);
            const Vector6 u = ges.eigenvectors().col(d);
            json dir = {{"lambda", lambda}};
            for (const auto& name : parts) {
              const double z = u.dot(g[name]) / std::sqrt(std::max(lambda, 1e-30));
              dir["z_" + name] = z;
              acc.Add(Band(lambda) + " z_" + name, z);
            }
            const double inflation = u.dot(V * u) / std::max(lambda, 1e-30);
            const double inflation1 = u.dot(V1 * u) / std::max(lambda, 1e-30);
            dir["sandwich_block"] = inflation;
            dir["sandwich_point"] = inflation1;
            acc.Add(Band(lambda) + " sandwich_block", inflation);
            acc.Add(Band(lambda) + " sandwich_point", inflation1);
            // What the pair would move along u (RMS displacement of its points, mm), and its predicted sd.
            double move = 0, sd = 0;
            const double alpha = u.dot(g["full"]) / std::max(lambda, 1e-30);
            for (std::size_t m = 0; m < members.size(); ++m) {
              const Eigen::Vector3d arm = probes[members[m]].p - centre;
              const Eigen::Vector3d dx = u.head<3>().cross(arm) + u.tail<3>();
              move += dx.squaredNorm();
            }
            move = std::sqrt(move / double(members.size()));
            sd = move / std::sqrt(std::max(lambda, 1e-30));
            dir["move_mm"] = std::abs(alpha) * move;
            dir["sd_mm"] = sd;
            dirs.push_back(dir);
          }
          pair["directions"] = dirs;
          json corr_json = json::array();
          for (std::size_t b = 0; b < bins.size(); ++b)
            corr_json.push_back({{"to_spacings", bins[b]},
                                 {"corr", cnt[b] ? cov[b] / cnt[b] / var : 0.0},
                                 {"pairs", cnt[b]}});
          pair["residual_correlation"] = corr_json;
          for (std::size_t b = 0; b < bins.size(); ++b)
            acc.Add("corr<" + std::to_string(int(bins[b])) + "sp", cnt[b] ? cov[b] / cnt[b] / var : 0.0);
          out.push_back(pair);
        }
        std::fprintf(stderr, "overlap %.2f %s seed %llu: %zu pairs, %zu correspondences, scale %.3f mm\n",
                     overlap, sampling.c_str(), static_cast<unsigned long long>(seed), groups.size(),
                     probes.size(), scale);
      }
    }
  }
  // Summary: RMS of each z-score per eigenvalue band (1 if the model is right), median inflations.
  for (const auto& [key, v] : acc.values) {
    std::fprintf(stderr, "%-32s n %4zu  rms %.3f  median %.3f\n", key.c_str(), v.size(), Rms(v), Median(v));
  }
  std::printf("%s\n", out.dump(1).c_str());
  return 0;
}
