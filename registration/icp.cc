#include "registration/icp.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <sstream>
#include <cstdio>
#include <cstdlib>

#include "registration/voxel_downsample.h"
#include "shape/core/error.h"

namespace pectus {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDegPerRad = 180.0 / kPi;
constexpr std::uint32_t kNoMatch = std::numeric_limits<std::uint32_t>::max();
// Correspondences are summed in blocks of this many, then the blocks in order: the same sums for any
// number of threads.
constexpr std::size_t kBlock = 512;

using Matrix6 = Eigen::Matrix<double, 6, 6>;
using Vector6 = Eigen::Matrix<double, 6, 1>;

double Seconds(std::chrono::steady_clock::time_point since) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - since).count();
}

// The normal equations of one block of correspondences.
struct BlockSum {
  Matrix6 H = Matrix6::Zero();
  Vector6 g = Vector6::Zero();
  double weighted_r2 = 0.0;
  double weight = 0.0;
  std::int64_t count = 0;
};

// The correspondences of one level at the current pose (arrays indexed like the level's points).
struct Pairs {
  std::vector<std::uint32_t> target;  // kNoMatch when dropped
  std::vector<Eigen::Vector3d> p;     // transformed source point (target's centred frame)
  std::vector<Eigen::Vector3d> n;     // normal of the residual (target's, or the symmetric one)
  std::vector<double> r;              // signed residual along n (mm)
  void Resize(std::size_t m) {
    target.resize(m);
    p.resize(m);
    n.resize(m);
    r.resize(m);
  }
};

// Everything one alignment needs, shared by the steps below.
struct Problem {
  const IcpTarget* target;
  const Points3* source;          // original positions
  const Points3* source_normals;  // may be empty
  Eigen::Vector3d source_origin;  // subtracted from source positions before the pose is applied
  const IcpOptions* options;
  double cos_max_normal_angle;    // -1 when the normal test is off
};

// Step 1: nearest target point of every level point within `gate`, and the residual along the normal.
void FindPairs(const Problem& pb, const std::vector<std::uint32_t>& level, const Rigid3& T, double gate, Pairs* pairs) {
  const Eigen::Matrix3d R = T.linear();
  const Eigen::Vector3d t = T.translation();
  const bool symmetric = pb.options->method == IcpMethod::kSymmetric;
  const bool use_source_normals = pb.source_normals->rows() > 0 && (symmetric || pb.cos_max_normal_angle > -1.0);
  const Points3& tp = pb.target->centred_positions();
  const Points3& tn = pb.target->normals();
  const auto m = static_cast<std::int64_t>(level.size());
#pragma omp parallel for schedule(static)
  for (std::int64_t k = 0; k < m; ++k) {
    const std::uint32_t i = level[static_cast<std::size_t>(k)];
    const Eigen::Vector3d p = R * (pb.source->row(i).transpose() - pb.source_origin) + t;
    std::uint32_t j = 0;
    double d2 = 0.0;
    pairs->target[static_cast<std::size_t>(k)] = kNoMatch;
    if (!pb.target->tree().NearestWithin(p, gate, &j, &d2)) continue;
    Eigen::Vector3d n = tn.row(j).transpose();
    if (n.squaredNorm() == 0.0) continue;
    if (use_source_normals) {
      Eigen::Vector3d ns = R * pb.source_normals->row(i).transpose();
      if (ns.squaredNorm() == 0.0) continue;
      const double c = ns.dot(n);
      if (std::abs(c) < pb.cos_max_normal_angle) continue;
      if (symmetric) {
        // Rusinkiewicz (2019), Eq. (6): the sum of both normals, flipped to agree; normalised so that the
        // residual stays a distance in mm.
        if (c < 0.0) ns = -ns;
        n = (n + ns).normalized();
      }
    }
    const std::size_t s = static_cast<std::size_t>(k);
    pairs->target[s] = j;
    pairs->p[s] = p;
    pairs->n[s] = n;
    pairs->r[s] = (p - tp.row(j).transpose()).dot(n);
  }
}

// Step 2: the robust scale (MAD of the residuals) and the trimming threshold. Returns how many pairs.
std::int64_t RobustScale(const Pairs& pairs, const IcpOptions& options, double* scale, double* trim_threshold) {
  std::vector<double> abs_r;
  abs_r.reserve(pairs.r.size());
  for (std::size_t k = 0; k < pairs.r.size(); ++k) {
    if (pairs.target[k] != kNoMatch) abs_r.push_back(std::abs(pairs.r[k]));
  }
  const auto count = static_cast<std::int64_t>(abs_r.size());
  *trim_threshold = std::numeric_limits<double>::infinity();
  if (count > 0 && options.trim_fraction > 0.0) {
    const auto keep = static_cast<std::size_t>(std::ceil((1.0 - options.trim_fraction) * static_cast<double>(count)));
    auto nth = abs_r.begin() + static_cast<std::ptrdiff_t>(std::max<std::size_t>(keep, 1) - 1);
    std::nth_element(abs_r.begin(), nth, abs_r.end());
    *trim_threshold = *nth;
  }
  *scale = std::max(MadScale(&abs_r), options.min_robust_scale_mm);
  return count;
}

// Step 3: the weighted normal equations H x = -g of the linearised residuals, Chen and Medioni (1992)
// for point-to-plane (J = [p x n, n]) and Rusinkiewicz (2019), Eq. (9), for symmetric (J = [(p+q) x n, n]).
BlockSum Accumulate(const Problem& pb, const Pairs& pairs, double scale, double trim_threshold) {
  const IcpOptions& o = *pb.options;
  const double c = RobustTuningConstant(o.loss) * scale;
  const bool symmetric = o.method == IcpMethod::kSymmetric;
  const Points3& tp = pb.target->centred_positions();
  const std::size_t m = pairs.r.size();
  const std::size_t blocks = (m + kBlock - 1) / kBlock;
  std::vector<BlockSum> sums(blocks);
#pragma omp parallel for schedule(static)
  for (std::int64_t b = 0; b < static_cast<std::int64_t>(blocks); ++b) {
    BlockSum& s = sums[static_cast<std::size_t>(b)];
    const std::size_t end = std::min(m, (static_cast<std::size_t>(b) + 1) * kBlock);
    for (std::size_t k = static_cast<std::size_t>(b) * kBlock; k < end; ++k) {
      if (pairs.target[k] == kNoMatch || std::abs(pairs.r[k]) > trim_threshold) continue;
      const double r = pairs.r[k];
      const double w = RobustWeight(o.loss, r, c);
      if (w <= 0.0) continue;
      const Eigen::Vector3d& n = pairs.n[k];
      const Eigen::Vector3d arm = symmetric ? Eigen::Vector3d(pairs.p[k] + tp.row(pairs.target[k]).transpose())
                                            : pairs.p[k];
      Vector6 J;
      J << arm.cross(n), n;
      s.H.noalias() += w * J * J.transpose();
      s.g.noalias() += (w * r) * J;
      s.weighted_r2 += w * r * r;
      s.weight += w;
      ++s.count;
    }
  }
  BlockSum total;
  for (const BlockSum& s : sums) {
    total.H += s.H;
    total.g += s.g;
    total.weighted_r2 += s.weighted_r2;
    total.weight += s.weight;
    total.count += s.count;
  }
  return total;
}

// Smallest over largest eigenvalue of H with the rotation rows scaled by a length, so that rotation
// (mm per radian) and translation (mm per mm) are comparable. Near 0: a sliding direction.
double Conditioning(const Matrix6& H, double length) {
  Vector6 d;
  d << Eigen::Vector3d::Constant(1.0 / length), Eigen::Vector3d::Ones();
  const Matrix6 Hs = d.asDiagonal() * H * d.asDiagonal();
  Eigen::SelfAdjointEigenSolver<Matrix6> eig(Hs, Eigen::EigenvaluesOnly);
  const double hi = eig.eigenvalues()(5);
  return hi > 0.0 ? std::max(0.0, eig.eigenvalues()(0)) / hi : 0.0;
}

// Step 4: the incremental pose from the solution x of the normal equations.
Rigid3 Increment(const Vector6& x, IcpMethod method) {
  Rigid3 dT = Rigid3::Identity();
  const Eigen::Vector3d a = x.head<3>();
  const double norm = a.norm();
  if (method == IcpMethod::kPointToPlane) {
    if (norm > 0.0) dT.linear() = Eigen::AngleAxisd(norm, a / norm).toRotationMatrix();
    dT.translation() = x.tail<3>();
    return dT;
  }
  // Rusinkiewicz (2019), Sec. 3.2: x = (a tan(theta), t / cos(theta)); the update is R T(t) R with R the
  // rotation by theta about a (half of the rotation applied to each surface).
  const double theta = std::atan(norm);
  Rigid3 half = Rigid3::Identity();
  if (norm > 0.0) half.linear() = Eigen::AngleAxisd(theta, a / norm).toRotationMatrix();
  Rigid3 shift = Rigid3::Identity();
  shift.translation() = x.tail<3>() * std::cos(theta);
  return half * shift * half;
}

double RotationAngleDeg(const Eigen::Matrix3d& R) {
  return Eigen::AngleAxisd(R).angle() * kDegPerRad;
}

// Source rows within the patches (all rows when there are none).
std::vector<std::uint32_t> PatchRows(const Points3& source, const IcpOptions& o) {
  std::vector<std::uint32_t> rows;
  rows.reserve(static_cast<std::size_t>(source.rows()));
  const double r2 = o.patch_radius_mm * o.patch_radius_mm;
  for (Eigen::Index i = 0; i < source.rows(); ++i) {
    bool inside = o.patch_centres.empty();
    for (const Eigen::Vector3d& c : o.patch_centres) {
      if ((source.row(i).transpose() - c).squaredNorm() <= r2) {
        inside = true;
        break;
      }
    }
    if (inside) rows.push_back(static_cast<std::uint32_t>(i));
  }
  return rows;
}

std::string Format(double value, int precision = 3) {
  std::ostringstream s;
  s.precision(precision);
  s << value;
  return s.str();
}

}  // namespace

IcpMethod ParseIcpMethod(const std::string& name) {
  if (name == "point-to-plane") return IcpMethod::kPointToPlane;
  if (name == "symmetric") return IcpMethod::kSymmetric;
  ThrowUsage("unknown ICP method '" + name + "' (point-to-plane, symmetric)");
}

std::string ToString(IcpMethod method) {
  return method == IcpMethod::kSymmetric ? "symmetric" : "point-to-plane";
}

bool IcpOptions::IsValid(std::string* why) const {
  auto fail = [&](const std::string& text) {
    if (why) *why = text;
    return false;
  };
  auto positive = [](double v) { return v > 0.0 && std::isfinite(v); };
  if (!(min_robust_scale_mm > 0.0)) return fail("min_robust_scale_mm must be > 0");
  if (!(trim_fraction >= 0.0 && trim_fraction <= 0.9)) return fail("trim_fraction must be in [0, 0.9]");
  if (!(max_normal_angle_deg >= 0.0 && max_normal_angle_deg <= 90.0)) {
    return fail("max_normal_angle_deg must be in [0, 90]");
  }
  for (std::size_t i = 0; i < levels.size(); ++i) {
    const IcpLevel& l = levels[i];
    const std::string at = "level " + std::to_string(i + 1) + ": ";
    if (!(l.voxel_size_mm >= 0.0) || !std::isfinite(l.voxel_size_mm)) return fail(at + "voxel_size_mm must be >= 0");
    if (!positive(l.max_distance_mm)) return fail(at + "max_distance_mm must be > 0");
    if (l.max_iterations < 1) return fail(at + "max_iterations must be >= 1");
  }
  if (levels.empty()) {
    if (auto_level_points.empty()) return fail("auto_level_points must not be empty when levels is");
    for (int n : auto_level_points) {
      if (n < 10) return fail("auto_level_points must each be >= 10");
    }
    if (!positive(initial_max_distance_mm)) return fail("initial_max_distance_mm must be > 0");
    if (auto_max_iterations < 1) return fail("auto_max_iterations must be >= 1");
  }
  if (!positive(rotation_tolerance_deg)) return fail("rotation_tolerance_deg must be > 0");
  if (!positive(translation_tolerance_mm)) return fail("translation_tolerance_mm must be > 0");
  if (!patch_centres.empty() && !positive(patch_radius_mm)) return fail("patch_radius_mm must be > 0 with patches");
  for (const auto& c : patch_centres) {
    if (!c.allFinite()) return fail("patch centres must be finite");
  }
  if (!positive(max_rms_mm)) return fail("max_rms_mm must be > 0");
  if (!(min_inlier_fraction >= 0.0 && min_inlier_fraction <= 1.0)) return fail("min_inlier_fraction must be in [0, 1]");
  if (!(inlier_distance_mm >= 0.0) || !std::isfinite(inlier_distance_mm)) return fail("inlier_distance_mm must be >= 0");
  if (!(min_conditioning >= 0.0 && min_conditioning < 1.0)) return fail("min_conditioning must be in [0, 1)");
  if (min_correspondences < 6) return fail("min_correspondences must be >= 6");
  return true;
}

std::string IcpResult::BriefReport() const {
  std::ostringstream s;
  s.precision(3);
  s << (success ? "success" : "FAILED") << ", " << (converged ? "converged" : "not converged") << ", " << iterations
    << " iterations, RMS " << rms_mm << " mm, " << 100.0 * inlier_fraction << " % inliers";
  if (!success) s << ": " << message;
  return s.str();
}

void IcpTarget::Prepare(const Points3& positions, const std::string& name) {
  const auto start = std::chrono::steady_clock::now();
  if (positions.rows() < 3) ThrowBadInput(name, "an ICP target needs at least 3 points");
  if (!positions.allFinite()) ThrowBadInput(name, "a position is not finite");
  origin_ = positions.colwise().mean().transpose();
  centred_ = positions.rowwise() - origin_.transpose();
  tree_ = std::make_unique<KdTree3>(centred_);
  spacing_mm_ = MedianPointSpacing(centred_, *tree_);
  seconds_ = Seconds(start);
}

IcpTarget::IcpTarget(const Points3& positions, const Points3& normals, const std::string& name) {
  if (normals.rows() != positions.rows()) {
    ThrowBadInput(name, "has " + std::to_string(positions.rows()) + " points but " + std::to_string(normals.rows()) +
                            " normals");
  }
  if (!normals.allFinite()) ThrowBadInput(name, "a normal is not finite");
  Prepare(positions, name);
  const auto start = std::chrono::steady_clock::now();
  normals_ = normals;
  seconds_ += Seconds(start);
}

IcpTarget::IcpTarget(const Points3& positions, const NormalOptions& normal_options, const std::string& name) {
  Prepare(positions, name);
  NormalOptions o = normal_options;
  o.viewpoint -= origin_;
  NormalResult normals = EstimateNormals(centred_, o, tree_.get());
  normals_ = std::move(normals.normals);
  normal_seconds_ = normals.seconds;
}

IcpTarget::~IcpTarget() = default;

std::vector<IcpLevel> IcpLevelsFor(const IcpOptions& o, Eigen::Index source_points, double spacing) {
  if (!o.levels.empty()) return o.levels;
  std::vector<IcpLevel> levels;
  // The source covers about source_points * spacing^2 of surface (same density as the target); a voxel
  // of side v then keeps about that area / v^2 points.
  const double area = static_cast<double>(source_points) * spacing * spacing;
  double gate = o.initial_max_distance_mm;
  for (const int count : o.auto_level_points) {
    IcpLevel l;
    l.voxel_size_mm = source_points > count && spacing > 0.0 ? std::sqrt(area / count) : 0.0;
    l.max_distance_mm = std::max(gate, 3.0 * spacing);
    l.max_iterations = o.auto_max_iterations;
    levels.push_back(l);
    gate /= 4.0;
  }
  return levels;
}

IcpResult AlignIcp(const IcpTarget& target, const Points3& source_positions, const Points3& source_normals,
                   const Rigid3& T_target_source_initial, const IcpOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  std::string why;
  if (!options.IsValid(&why)) ThrowUsage("ICP: " + why);
  if (source_normals.rows() != 0 && source_normals.rows() != source_positions.rows()) {
    ThrowBadInput("ICP source", "has " + std::to_string(source_positions.rows()) + " points but " +
                                    std::to_string(source_normals.rows()) + " normals");
  }
  if (options.method == IcpMethod::kSymmetric && source_normals.rows() == 0) {
    ThrowBadInput("ICP source", "symmetric ICP needs source normals");
  }
  if (!source_positions.allFinite() || !source_normals.allFinite()) {
    ThrowBadInput("ICP source", "a position or normal is not finite");
  }
  if (!T_target_source_initial.matrix().allFinite()) ThrowBadInput("ICP", "the initial pose is not finite");

  IcpResult result;
  result.T_target_source = T_target_source_initial;
  auto finish = [&](const std::string& message) {
    result.message = message;
    result.seconds = Seconds(start);
    return result;
  };

  // Work in the target's centred frame with a centred source: x_c = T_c (x - source_origin), where
  // T_c = T(-target_origin) T T(source_origin). Far-away frames cancel before any product is formed.
  const std::vector<std::uint32_t> considered = PatchRows(source_positions, options);
  if (considered.size() < static_cast<std::size_t>(options.min_correspondences)) {
    return finish("only " + std::to_string(considered.size()) + " source points" +
                  (options.patch_centres.empty() ? "" : " inside the patches") + "; need at least " +
                  std::to_string(options.min_correspondences));
  }
  Eigen::Vector3d source_origin = Eigen::Vector3d::Zero();
  for (const std::uint32_t i : considered) source_origin += source_positions.row(i).transpose();
  source_origin /= static_cast<double>(considered.size());
  Rigid3 shift_target = Rigid3::Identity(), shift_source = Rigid3::Identity();
  shift_target.translation() = -target.origin();
  shift_source.translation() = source_origin;
  Rigid3 T = shift_target * T_target_source_initial * shift_source;

  // Coarse-to-fine sampling: the finest level from the considered points, coarser ones from it. An
  // automatic level's voxel is an estimate from the point spacing; one correction brings its count near
  // the requested one (a surface keeps about area / voxel^2 points).
  std::vector<IcpLevel> levels = IcpLevelsFor(options, static_cast<Eigen::Index>(considered.size()), target.spacing_mm());
  std::vector<std::vector<std::uint32_t>> samples(levels.size());
  for (std::size_t l = levels.size(); l-- > 0;) {
    const std::vector<std::uint32_t>& finer = l + 1 < levels.size() ? samples[l + 1] : considered;
    if (levels[l].voxel_size_mm <= 0.0) {
      samples[l] = finer;
      continue;
    }
    samples[l] = VoxelDownsample(source_positions, levels[l].voxel_size_mm, &finer);
    if (options.levels.empty()) {
      const double wanted = options.auto_level_points[l];
      const double ratio = static_cast<double>(samples[l].size()) / wanted;
      if (ratio > 1.25 && finer.size() > wanted) {
        levels[l].voxel_size_mm *= std::sqrt(ratio);
        samples[l] = VoxelDownsample(source_positions, levels[l].voxel_size_mm, &finer);
      }
    }
  }

  Problem pb{&target, &source_positions, &source_normals, source_origin, &options,
             options.max_normal_angle_deg > 0.0 ? std::cos(options.max_normal_angle_deg / kDegPerRad) : -1.0};
  Pairs pairs;
  Matrix6 last_H = Matrix6::Zero();
  double length = 1.0;
  for (std::size_t l = 0; l < levels.size(); ++l) {
    const IcpLevel& level = levels[l];
    const std::vector<std::uint32_t>& sample = samples[l];
    // Coarser levels need only bring the pose into the next level's reach: tolerances ten times looser
    // per level above the last.
    const double looser = std::pow(10.0, static_cast<double>(levels.size() - 1 - l));
    const double rot_tol = options.rotation_tolerance_deg * looser;
    const double trans_tol = options.translation_tolerance_mm * looser;
    IcpLevelReport report;
    report.voxel_size_mm = level.voxel_size_mm;
    report.max_distance_mm = level.max_distance_mm;
    report.source_points = static_cast<std::int64_t>(sample.size());
    pairs.Resize(sample.size());
    Rigid3 previous = T;
    for (int it = 0; it < level.max_iterations; ++it) {
      FindPairs(pb, sample, T, level.max_distance_mm, &pairs);  // step 1
      double scale = 0.0, trim = 0.0;
      const std::int64_t count = RobustScale(pairs, options, &scale, &trim);  // step 2
      if (count < options.min_correspondences) {
        result.levels.push_back(report);
        result.T_target_source = Rigid3(shift_target.inverse() * T * shift_source.inverse());
        return finish("only " + std::to_string(count) + " source points have a target point within " +
                      Format(level.max_distance_mm) + " mm at level " + std::to_string(l + 1) +
                      "; the surfaces do not overlap at this pose");
      }
      const BlockSum sum = Accumulate(pb, pairs, scale, trim);  // step 3
      if (sum.count < options.min_correspondences) {
        result.levels.push_back(report);
        return finish("the robust loss rejected all but " + std::to_string(sum.count) + " correspondences");
      }
      length = 0.0;
      for (std::size_t k = 0; k < pairs.p.size(); ++k) {
        if (pairs.target[k] != kNoMatch) length += pairs.p[k].squaredNorm();
      }
      length = std::max(std::sqrt(length / static_cast<double>(count)), 1e-9);
      last_H = sum.H;
      const Vector6 x = sum.H.ldlt().solve(-sum.g);
      if (!x.allFinite()) {
        result.levels.push_back(report);
        return finish("the normal equations are singular at level " + std::to_string(l + 1) +
                      " (the overlap does not fix all six degrees of freedom)");
      }
      const Rigid3 dT = Increment(x, options.method);  // step 4
      const Rigid3 before_previous = previous;
      previous = T;
      T = dT * T;
      ++report.iterations;
      ++result.iterations;
      report.rms_mm = std::sqrt(sum.weighted_r2 / sum.weight);
      if (std::getenv("PECTUS_ICP_DEBUG")) fprintf(stderr, "L%zu it%d n=%ld scale=%.4f rms=%.4f drot=%.2e dtr=%.2e\n", l, it, (long)sum.count, scale, report.rms_mm, RotationAngleDeg(dT.linear()), dT.translation().norm());
      // Stop on a small update, or on a two-step cycle between correspondence sets (the pose back where
      // it was two iterations ago): nearest-neighbour pairing is discrete, so ICP may alternate forever.
      const Rigid3 cycle = T * before_previous.inverse();
      if ((RotationAngleDeg(dT.linear()) < rot_tol && dT.translation().norm() < trans_tol) ||
          (it >= 2 && RotationAngleDeg(cycle.linear()) < rot_tol && cycle.translation().norm() < trans_tol)) {
        report.converged = true;
        break;
      }
    }
    result.levels.push_back(report);
  }
  result.T_target_source = Rigid3(shift_target.inverse() * T * shift_source.inverse());
  result.converged = result.levels.back().converged;
  result.conditioning = Conditioning(last_H, length);

  // Final figures on the finest sample at the final pose: inliers within reach, their RMS distance.
  const double reach = options.inlier_distance_mm > 0.0 ? options.inlier_distance_mm : levels.back().max_distance_mm;
  FindPairs(pb, samples.back(), T, reach, &pairs);
  double r2 = 0.0;
  for (std::size_t k = 0; k < pairs.r.size(); ++k) {
    if (pairs.target[k] == kNoMatch) continue;
    ++result.inliers;
    r2 += pairs.r[k] * pairs.r[k];
  }
  result.inlier_fraction = static_cast<double>(result.inliers) / static_cast<double>(samples.back().size());
  result.rms_mm = result.inliers > 0 ? std::sqrt(r2 / static_cast<double>(result.inliers)) : 0.0;

  // Acceptance: a poor fit is a failure with its reason, never a quiet success.
  std::vector<std::string> problems;
  if (!result.converged) {
    problems.push_back("did not converge in " + std::to_string(levels.back().max_iterations) +
                       " iterations at the last level");
  }
  if (result.rms_mm > options.max_rms_mm) {
    problems.push_back("RMS distance " + Format(result.rms_mm) + " mm exceeds " + Format(options.max_rms_mm) + " mm");
  }
  if (result.inlier_fraction < options.min_inlier_fraction) {
    problems.push_back("only " + Format(100.0 * result.inlier_fraction) + " % of the source lies within " +
                       Format(reach) + " mm of the target (need " + Format(100.0 * options.min_inlier_fraction) +
                       " %)");
  }
  if (result.conditioning < options.min_conditioning) {
    problems.push_back("the overlap leaves a sliding direction (conditioning " + Format(result.conditioning) +
                       " < " + Format(options.min_conditioning) + ")");
  }
  result.success = problems.empty();
  std::string message;
  if (result.success) {
    message = "converged in " + std::to_string(result.iterations) + " iterations: RMS " + Format(result.rms_mm) +
              " mm, " + Format(100.0 * result.inlier_fraction) + " % inliers";
  } else {
    for (const auto& p : problems) message += (message.empty() ? "" : "; ") + p;
  }
  return finish(message);
}

}  // namespace pectus
