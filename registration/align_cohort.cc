#include "registration/align_cohort.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>
#include <iterator>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>

#include "registration/pose_error.h"
#include "registration/voxel_downsample.h"
#include "shape/core/atomic_file.h"
#include "shape/core/error.h"
#include "shape/core/log.h"

namespace pectus {
namespace {
namespace fs = std::filesystem;

// One scan's fit: to the reference (RegisterPair), or of the mean onto it in a groupwise round (AlignIcp).
struct ScanFit {
  Similarity3 T;
  bool success = false;
  std::string message;
  double rms_mm = 0.0, inlier_fraction = 1.0;
};

// The scans' fits of one phase: in memory, or one file per scan committed to `folder/NAME.fit` as it
// finishes (CBOR: every double bit for bit, so a fit read back is the fit computed).
class FitStore {
 public:
  FitStore(const fs::path& folder, const std::vector<CohortScan>& scans)
      : folder_(folder), held_(scans.size()) {
    for (const CohortScan& s : scans) names_.push_back(s.name);
  }
  bool Has(std::size_t i) const {
    std::error_code ec;
    return folder_.empty() ? held_[i].has_value() : fs::exists(Path(i), ec);
  }
  void Put(std::size_t i, const ScanFit& fit) {
    if (folder_.empty()) {
      held_[i] = fit;
      return;
    }
    const Eigen::Matrix3d& R = fit.T.rotation;
    const nlohmann::json j = {
        {"scale", fit.T.scale},
        {"rotation", std::vector<double>(R.data(), R.data() + 9)},
        {"translation", {fit.T.translation.x(), fit.T.translation.y(), fit.T.translation.z()}},
        {"success", fit.success},
        {"message", fit.message},
        {"rms_mm", fit.rms_mm},
        {"inlier_fraction", fit.inlier_fraction}};
    const std::vector<std::uint8_t> bytes = nlohmann::json::to_cbor(j);
    fs::create_directories(folder_);
    WriteFileAtomically(Path(i), std::string_view(reinterpret_cast<const char*>(bytes.data()), bytes.size()));
  }
  ScanFit Get(std::size_t i) const {
    if (folder_.empty()) return *held_[i];
    std::ifstream in(Path(i), std::ios::binary);
    if (!in) ThrowBadInput(Path(i).string(), "cannot be read (a scan's fit of `pectus register`)");
    const std::vector<std::uint8_t> bytes((std::istreambuf_iterator<char>(in)),
                                          std::istreambuf_iterator<char>());
    const nlohmann::json j = nlohmann::json::from_cbor(bytes, true, false);
    ScanFit fit;
    try {
      if (j.is_discarded()) throw std::runtime_error("not CBOR");
      fit.T.scale = j.at("scale").get<double>();
      const auto R = j.at("rotation").get<std::vector<double>>();
      const auto t = j.at("translation").get<std::vector<double>>();
      if (R.size() != 9 || t.size() != 3) throw std::runtime_error("wrong sizes");
      fit.T.rotation = Eigen::Map<const Eigen::Matrix3d>(R.data());
      fit.T.translation = Eigen::Vector3d(t[0], t[1], t[2]);
      fit.success = j.at("success").get<bool>();
      fit.message = j.at("message").get<std::string>();
      fit.rms_mm = j.at("rms_mm").get<double>();
      fit.inlier_fraction = j.at("inlier_fraction").get<double>();
    } catch (const std::exception& e) {
      ThrowBadInput(Path(i).string(), std::string("is not a scan's fit of `pectus register` (") + e.what() +
                                          "); remove the work folder and run again");
    }
    return fit;
  }

 private:
  fs::path Path(std::size_t i) const { return folder_ / (names_[i] + ".fit"); }
  fs::path folder_;
  std::vector<std::string> names_;
  std::vector<std::optional<ScanFit>> held_;
};

ScanFit FitOf(const PairRegistrationResult& r) {
  ScanFit fit;
  fit.T = r.T_target_source;
  fit.success = r.success;
  fit.message = r.message;
  if (r.icp) {
    fit.rms_mm = r.icp->rms_mm;
    fit.inlier_fraction = r.icp->inlier_fraction;
  }
  return fit;
}

// The phase folders of a work folder: to-reference and groupwise-1, -2, ...
std::vector<fs::path> FitFolders(const fs::path& work) {
  std::vector<fs::path> folders;
  std::error_code ec;
  for (fs::directory_iterator it(work, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (name == "to-reference" || name.rfind("groupwise-", 0) == 0) folders.push_back(it->path());
  }
  return folders;
}

}  // namespace

void RemoveCohortFits(const fs::path& work) {
  std::error_code ec;
  for (const fs::path& folder : FitFolders(work)) {
    fs::remove_all(folder, ec);
    if (ec) ThrowFailure("cannot remove the scans' fits: " + ec.message(), folder.string());
  }
  if (fs::is_empty(work, ec)) fs::remove(work, ec);
}

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

CohortResult AlignCohort(const std::vector<CohortScan>& scans, const CohortOptions& options,
                         const CohortFarm& farm) {
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
  SerialTaskRunner threads;
  TaskRunner& runner = farm.runner != nullptr ? *farm.runner : threads;
  if (runner.Processes() > 1 && farm.work.empty())
    ThrowUsage("cohort registration on several processes needs a work folder they all see");
  if ((farm.fits_only || farm.gather) && (farm.work.empty() || options.mode != CohortMode::kToReference))
    ThrowUsage("cohort registration in shares is for the registration to a reference, with a work folder");
  if (!farm.work.empty() && !farm.resume && !farm.fits_only && !farm.gather && runner.IsLeader())
    RemoveCohortFits(farm.work);
  runner.Barrier();
  auto phase = [&](const std::string& name) { return farm.work.empty() ? fs::path() : farm.work / name; };
  // The scans handed out largest first, so that the last to finish are small ones.
  std::vector<double> sizes(n);
  for (std::size_t i = 0; i < n; ++i) sizes[i] = static_cast<double>(scans[i].cloud.size());
  const std::vector<int> largest_first = LargestFirst(sizes);

  CohortResult result;
  result.T_frame_scan.assign(n, Similarity3{});
  result.success.assign(n, true);
  result.messages.assign(n, "reference");
  result.rms_mm.assign(n, 0.0);
  result.inlier_fraction.assign(n, 1.0);
  auto record = [&](std::size_t i, const ScanFit& fit) {
    result.T_frame_scan[i] = fit.T;
    result.success[i] = fit.success;
    result.messages[i] = fit.message;
    result.rms_mm[i] = fit.rms_mm;
    result.inlier_fraction[i] = fit.inlier_fraction;
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
    FitStore fits(phase("to-reference"), scans);
    std::vector<int> todo;
    for (int i : largest_first) {
      if (static_cast<std::size_t>(i) != ref && !fits.Has(static_cast<std::size_t>(i))) todo.push_back(i);
    }
    if (farm.gather && !todo.empty()) {
      std::string names;
      for (std::size_t k = 0; k < std::min<std::size_t>(todo.size(), 10); ++k)
        names += (k == 0 ? "" : ", ") + scans[static_cast<std::size_t>(todo[k])].name;
      if (todo.size() > 10) names += " and " + std::to_string(todo.size() - 10) + " more";
      ThrowUsage("--gather: no share has registered scan(s) " + names + " (their fits are not in " +
                 farm.work.string() + "); run their shares, or the whole run with --resume");
    }
    Progress progress("registering to " + r.name, static_cast<std::int64_t>(todo.size()));
    runner.Run(todo, [&](int i) {
      const CohortScan& s = scans[static_cast<std::size_t>(i)];
      fits.Put(static_cast<std::size_t>(i),
               FitOf(RegisterPair(target, s.cloud, landmarks ? &*r.landmarks : nullptr,
                                  landmarks ? &*s.landmarks : nullptr, Similarity3{}, options.pair)));
      progress.Advance();
    });
    if (farm.fits_only) return CohortResult{};
    for (std::size_t i = 0; i < n; ++i) {
      if (i != ref) record(i, fits.Get(i));
    }
    runner.Barrier();  // every process has read the fits before the leader may remove them
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

    // Every scan to the mean: ICP of the mean points onto the scan, inverted (the scans on the farm).
    FitStore round(phase("groupwise-" + std::to_string(result.iterations)), scans);
    std::vector<int> todo;
    for (int i : largest_first) {
      if (!round.Has(static_cast<std::size_t>(i))) todo.push_back(i);
    }
    runner.Run(todo, [&](int index) {
      const auto i = static_cast<std::size_t>(index);
      const IcpResult r = AlignIcp(*targets[i], mean, Points3(), rigid[i].inverse(), icp);
      round.Put(
          i, {Similarity3::FromRigid(r.T_target_source), r.success, r.message, r.rms_mm, r.inlier_fraction});
    });
    double moved = 0.0;
    for (std::size_t i = 0; i < n; ++i) {
      const ScanFit fit = round.Get(i);
      moved = std::max(moved, RmsDisplacement(mean, Similarity3::FromRigid(rigid[i].inverse()), fit.T));
      rigid[i] = fit.T.RigidPart().inverse();
      result.success[i] = fit.success;
      result.messages[i] = fit.message;
      result.rms_mm[i] = fit.rms_mm;
      result.inlier_fraction[i] = fit.inlier_fraction;
    }
    runner.Barrier();  // every process has read the round's fits before the leader may remove them
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
