#include "registration/align_cohort.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <sstream>

#include "registration/pose_error.h"
#include "registration/voxel_downsample.h"
#include "shape/core/error.h"
#include "shape/core/log.h"

namespace pectus {

bool CohortOptions::IsValid(std::string* why) const {
  auto fail = [&](const char* text) {
    if (why) *why = text;
    return false;
  };
  if (!pair.IsValid(why)) return false;
  if (reference < 0) return fail("reference must be >= 0");
  if (max_groupwise_iterations < 1) return fail("max_groupwise_iterations must be >= 1");
  if (!(groupwise_tolerance_mm > 0.0)) return fail("groupwise_tolerance_mm must be > 0");
  if (mean_points < 10) return fail("mean_points must be >= 10");
  if (!(mean_max_distance_mm > 0.0)) return fail("mean_max_distance_mm must be > 0");
  return true;
}

bool CohortResult::all_succeeded() const {
  return std::all_of(success.begin(), success.end(), [](bool s) { return s; });
}

std::string CohortResult::BriefReport() const {
  const auto good = std::count(success.begin(), success.end(), true);
  std::ostringstream s;
  s.precision(3);
  s << good << " of " << success.size() << " scans registered";
  if (procrustes) s << ", landmark Procrustes RMS " << procrustes->rms_mm << " mm";
  if (iterations > 0) s << ", " << iterations << " groupwise rounds" << (converged ? "" : " (not settled)");
  s << ", " << timings_s.Total() << " s";
  return s.str();
}

CohortResult AlignCohort(const std::vector<CohortScan>& scans, const CohortOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) ThrowUsage("cohort registration: " + why);
  const std::size_t n = scans.size();
  const auto ref = static_cast<std::size_t>(options.reference);
  if (n < 2) ThrowUsage("cohort registration needs at least two scans");
  if (ref >= n) ThrowUsage("cohort registration: reference index out of range");
  const std::size_t with_landmarks = static_cast<std::size_t>(
      std::count_if(scans.begin(), scans.end(), [](const CohortScan& s) { return s.landmarks.has_value(); }));
  if (with_landmarks != 0 && with_landmarks != n) {
    ThrowUsage("cohort registration: " + std::to_string(with_landmarks) + " of " + std::to_string(n) +
               " scans have landmarks; give landmarks for all scans or for none");
  }
  const bool landmarks = with_landmarks == n;

  CohortResult result;
  result.T_frame_scan.assign(n, Similarity3{});
  result.success.assign(n, true);
  result.messages.assign(n, "reference");
  result.rms_mm.assign(n, 0.0);
  result.inlier_fraction.assign(n, 1.0);
  auto record = [&](std::size_t i, const PairRegistrationResult& r) {
    result.T_frame_scan[i] = r.T_target_source;
    result.success[i] = r.success;
    result.messages[i] = r.message;
    if (r.icp) {
      result.rms_mm[i] = r.icp->rms_mm;
      result.inlier_fraction[i] = r.icp->inlier_fraction;
    }
  };

  // Every scan to the reference: the whole of kToReference, and the start of kGroupwise without landmarks.
  auto since = [](std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  };
  auto t0 = std::chrono::steady_clock::now();
  if (options.mode == CohortMode::kToReference || !landmarks) {
    const CohortScan& r = scans[ref];
    const IcpTarget target = r.cloud.has_normals()
                                 ? IcpTarget(r.cloud.positions, r.cloud.normals, r.name)
                                 : IcpTarget(r.cloud.positions, options.pair.normals, r.name);
    Progress progress("registering to " + r.name, static_cast<std::int64_t>(n));
    for (std::size_t i = 0; i < n; ++i) {
      if (i != ref) {
        const PairRegistrationResult pr =
            RegisterPair(target, scans[i].cloud, landmarks ? &*r.landmarks : nullptr,
                         landmarks ? &*scans[i].landmarks : nullptr, Similarity3{}, options.pair);
        record(i, pr);
      }
      progress.Advance();
    }
    result.timings_s.Add("register", since(t0));
    if (options.mode == CohortMode::kToReference) return result;
  } else {
    // Groupwise with landmarks: generalised Procrustes of the landmarks gives the start.
    std::vector<LandmarkSet> sets;
    std::vector<std::string> names;
    for (const CohortScan& s : scans) {
      sets.push_back(*s.landmarks);
      names.push_back(s.name);
    }
    ProcrustesOptions po;
    po.estimate_scale = options.pair.landmarks.estimate_scale;
    po.reference = options.reference;
    po.min_spread_ratio = options.pair.landmarks.min_spread_ratio;
    result.procrustes = GeneralisedProcrustes(sets, po, names);
    result.T_frame_scan = result.procrustes->T_mean_shape;
    for (std::size_t i = 0; i < n; ++i) result.messages[i] = "landmark Procrustes";
    result.timings_s.Add("procrustes", since(t0));
  }
  t0 = std::chrono::steady_clock::now();

  // Groupwise refinement on the surfaces. Each scan is prepared once as an ICP target (positions scaled by
  // its fixed scale); the mean surface, sampled at points of the reference scan, is moved onto each scan.
  std::vector<std::unique_ptr<IcpTarget>> targets(n);
  std::vector<Rigid3> rigid(n);  // scaled scan frame -> cohort frame
  for (std::size_t i = 0; i < n; ++i) {
    const double s = result.T_frame_scan[i].scale;
    const Points3 scaled = scans[i].cloud.positions * s;
    targets[i] = scans[i].cloud.has_normals()
                     ? std::make_unique<IcpTarget>(scaled, scans[i].cloud.normals, scans[i].name)
                     : std::make_unique<IcpTarget>(scaled, options.pair.normals, scans[i].name);
    rigid[i] = result.T_frame_scan[i].RigidPart();
  }
  const Points3& ref_points = scans[ref].cloud.positions;
  const double area = static_cast<double>(ref_points.rows()) * std::pow(targets[ref]->spacing_mm(), 2);
  const std::vector<std::uint32_t> rows =
      ref_points.rows() > options.mean_points
          ? VoxelDownsample(ref_points, std::sqrt(area / options.mean_points))
          : std::vector<std::uint32_t>();
  Points3 mean(rows.empty() ? ref_points.rows() : static_cast<Eigen::Index>(rows.size()), 3);
  for (Eigen::Index k = 0; k < mean.rows(); ++k) {
    mean.row(k) = ref_points.row(rows.empty() ? k : rows[static_cast<std::size_t>(k)]);
  }
  mean = result.T_frame_scan[ref].Apply(mean);

  IcpOptions icp = options.pair.icp;
  icp.patch_centres.clear();
  const Eigen::VectorXd no_weights;
  Progress progress("groupwise registration", options.max_groupwise_iterations);
  result.converged = false;
  for (result.iterations = 1; result.iterations <= options.max_groupwise_iterations; ++result.iterations) {
    // The mean surface: each mean point moves along the scans' normals by the average of its offsets to
    // their tangent planes at its nearest points (to the nearest point itself where a scan has no normal
    // there). Only normal motion: moving to the nearest samples would also slide the mean along the
    // surface by the sampling's accidents, and the cohort frame would be defined only up to that drift.
    Points3 sum = Points3::Zero(mean.rows(), 3);
    Eigen::VectorXi count = Eigen::VectorXi::Zero(mean.rows());
    for (std::size_t i = 0; i < n; ++i) {
      const Rigid3 to_scan = rigid[i].inverse();
      const IcpTarget& t = *targets[i];
      for (Eigen::Index k = 0; k < mean.rows(); ++k) {
        const Eigen::Vector3d q = to_scan * Eigen::Vector3d(mean.row(k).transpose()) - t.origin();
        std::uint32_t j = 0;
        double d2 = 0.0;
        if (!t.tree().NearestWithin(q, options.mean_max_distance_mm, &j, &d2)) continue;
        const Eigen::Vector3d offset = Eigen::Vector3d(t.centred_positions().row(j).transpose()) - q;
        const Eigen::Vector3d normal = t.normals().row(j).transpose();
        const Eigen::Vector3d along =
            normal.squaredNorm() > 0.0 ? Eigen::Vector3d(normal * normal.dot(offset)) : offset;
        sum.row(k) += (rigid[i].linear() * along).transpose();
        ++count(k);
      }
    }
    Points3 next = mean;
    for (Eigen::Index k = 0; k < mean.rows(); ++k) {
      if (2 * count(k) >= static_cast<int>(n)) next.row(k) += sum.row(k) / count(k);
    }
    // Gauge: the new mean placed on the old one, so that the cohort frame does not drift.
    next = UmeyamaAlignment(next, mean, no_weights, false, 0.0, "mean surface").Apply(next);
    mean = next;

    // Every scan to the mean: ICP of the mean points onto the scan, inverted.
    double moved = 0.0;
    for (std::size_t i = 0; i < n; ++i) {
      const IcpResult r = AlignIcp(*targets[i], mean, Points3(), rigid[i].inverse(), icp);
      const Rigid3 updated = r.T_target_source.inverse();
      moved = std::max(moved, RmsDisplacement(mean, Similarity3::FromRigid(rigid[i].inverse()),
                                              Similarity3::FromRigid(r.T_target_source)));
      rigid[i] = updated;
      result.success[i] = r.success;
      result.messages[i] = r.message;
      result.rms_mm[i] = r.rms_mm;
      result.inlier_fraction[i] = r.inlier_fraction;
    }
    progress.Advance();
    if (moved < options.groupwise_tolerance_mm) {
      result.converged = true;
      break;
    }
  }
  result.iterations = std::min(result.iterations, options.max_groupwise_iterations);
  // The cohort frame is the reference scan's frame in both modes: re-express everything relative to it.
  const Rigid3 gauge = rigid[ref].inverse();
  const double ref_scale = result.T_frame_scan[ref].scale;
  for (std::size_t i = 0; i < n; ++i) {
    Similarity3 T = Similarity3::FromRigid(gauge * rigid[i]);
    T.scale = result.T_frame_scan[i].scale / ref_scale;
    T.translation /= ref_scale;
    result.T_frame_scan[i] = T;
  }
  Similarity3 to_frame = Similarity3::FromRigid(gauge);
  to_frame.scale = 1.0 / ref_scale;
  to_frame.translation /= ref_scale;
  mean = to_frame.Apply(mean);
  if (!result.converged) {
    for (std::size_t i = 0; i < n; ++i) {
      if (result.success[i]) {
        result.success[i] = false;
        result.messages[i] = "groupwise registration did not settle in " +
                             std::to_string(options.max_groupwise_iterations) + " rounds";
      }
    }
  }
  result.mean_points = mean;
  result.timings_s.Add("groupwise", since(t0));
  return result;
}

}  // namespace pectus
