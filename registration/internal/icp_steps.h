// pectus: the steps of one ICP iteration (registration/icp.cc): correspondences with certified reuse,
// robust scale, normal equations, pose update. Internal to pectus::registration; the method and its
// equations: docs/registration.md.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <limits>
#include <vector>

#include "registration/icp.h"

namespace pectus::icp_detail {

class RadiusGrid;

constexpr double kPi = 3.14159265358979323846;
constexpr double kDegPerRad = 180.0 / kPi;
constexpr std::uint32_t kNoMatch = std::numeric_limits<std::uint32_t>::max();
// Correspondences are summed in blocks of this many, then the blocks in order: the same sums for any
// number of threads.
constexpr std::size_t kBlock = 512;
// Step 3 runs on several threads only for at least this many sample points: it costs about 0.05 us a
// point, so a coarse level's few thousand points take less time than waking the threads, and on a busy
// machine every fork and join may wait for a time slice.
constexpr std::int64_t kMinParallelPoints = 16384;
// Step 1 costs 1-5 us a point where it searches the tree (a sparse sample misses the caches at every
// search), so it runs on several threads from this many points: a chest's 10000-point level gains (17 to
// 11-14 ms), its 3000-point level did not (6-7 ms on one thread, 6-10 on two).
constexpr std::int64_t kMinParallelSearchPoints = 8192;
// Steps 1 and 3 hand out their points in chunks of at most this many, to whichever thread is free: when
// the machine is busy and a thread is not given a core, the others take its share instead of waiting for
// it (with static shares, the thread that finished first waited for the other's whole share at every
// join). Step 1 cuts a small sample into at least kMinChunks chunks, of at least kMinChunk points.
constexpr std::int64_t kChunk = 2048;
constexpr std::int64_t kMinChunk = 128;
constexpr std::int64_t kMinChunks = 8;
// Step 1 searches this many times the gate, so that a certificate holds while a point moves a little.
constexpr double kSearchRadiusOverGate = 1.5;
// The finer levels search a uniform grid of the target (internal/radius_grid.h) once their search radius is
// at most this many target spacings: a cell of that size holds a few tens of a scan's points, where a
// search scans a column or two; beyond it, the tree's search is cheaper.
constexpr double kGridMaxSpacings = 5.0;
// The grid is built only if its bounding box needs at most this many cells per target point (a few
// outliers far off would otherwise make it mostly empty cells).
constexpr std::size_t kGridMaxCellsPerPoint = 4;
// Step 2 estimates the robust scale from at most this many residuals.
constexpr std::size_t kScaleSamples = 16384;
// Step 4a extrapolates when two successive steps have at least this cosine, by at most this factor.
constexpr double kExtrapolationCosine = 0.8;
constexpr double kMaxExtrapolation = 4.0;

using Matrix6 = Eigen::Matrix<double, 6, 6>;
using Vector6 = Eigen::Matrix<double, 6, 1>;

// The normal equations of one block of correspondences.
struct BlockSum {
  Matrix6 H = Matrix6::Zero();
  Vector6 g = Vector6::Zero();
  double weighted_r2 = 0.0;
  double weight = 0.0;
  double arm2 = 0.0;  // sum of |p|^2 (mm^2): the lever of the rotation, for Conditioning
  std::int64_t count = 0;
};

// The correspondences of one level at the current pose (arrays indexed like the level's points).
struct Pairs {
  std::vector<std::uint32_t> target;  // kNoMatch when dropped
  std::vector<Eigen::Vector3d> p;     // transformed source point (target's centred frame)
  std::vector<Eigen::Vector3d> n;     // normal of the residual (target's, or the symmetric one)
  std::vector<double> r;              // signed residual along n (mm)
  std::vector<double> abs_r;          // scratch of step 2
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
  double cos_max_normal_angle;       // -1 when the normal test is off
  double max_tangential2;            // squared tangential reach (mm^2); infinity when off
  const RadiusGrid* grid = nullptr;  // the target binned for the finer levels' searches; may be null
  // The target's coarse sample when this level searches it instead of every point (found rows are the
  // target's); null otherwise.
  const CoarseTarget* coarse = nullptr;
};

// The correspondence certificates of one level: per sample point, where it was when last searched (`at`),
// the Candidates(plane_points) nearest target rows from there, closest first (`count` of them; fewer when
// fewer lie within `radius`), and `reach`, the distance from `at` to the next nearest target point (`radius`
// when there is none within it). Every target point but the candidates lies at least `reach` from `at`, so
// at least reach - |p - at| from the point's current position p: while the closest candidate (the plane's
// farthest, for a plane of several points) is nearer than that, they are the exact nearest target points
// (docs/registration.md, ICP-2), and step 1 searches the tree only for the points whose certificate has
// expired.
struct NearestCache {
  // Candidates kept: one more than the plane's points, so that a certificate survives when the plane's last
  // point and the next swap.
  static constexpr int kMaxCandidates = kMaxPlanePoints + 1;
  static int Candidates(int plane_points) { return plane_points + 1; }
  double radius = 0.0;  // search radius (mm), above the gate
  std::vector<Eigen::Vector3d> at;
  std::vector<std::array<std::uint32_t, kMaxCandidates>> candidates;
  std::vector<std::uint8_t> count;
  std::vector<double> reach;
  std::vector<std::uint8_t> valid;
  /// Certificates for `m` points searched within `search_radius`, keeping those of the first `kept`
  /// points (a coarser level's sample that is a prefix of this one): a certificate stays exact whatever
  /// the radius it was made with, since its reach is at most that radius.
  void Reset(std::size_t m, double search_radius, std::size_t kept = 0) {
    radius = search_radius;
    kept = std::min(kept, valid.size());
    at.resize(m);
    candidates.resize(m);
    count.resize(m);
    reach.resize(m);
    valid.resize(m);
    std::fill(valid.begin() + static_cast<std::ptrdiff_t>(std::min(kept, m)), valid.end(), 0);
  }
};

// Step 1: nearest target point of every sample point within `gate`, and the residual along the normal;
// reuses `cache` certificates when given (nullptr: search every point). Returns the number of tree searches.
std::int64_t FindPairs(const Problem& pb, const std::vector<std::uint32_t>& sample, const Rigid3& T,
                       double gate, NearestCache* cache, Pairs* pairs);
// Step 2: the robust scale (MAD of the residuals) and the trimming threshold. Returns how many pairs.
std::int64_t RobustScale(const IcpOptions& options, Pairs* pairs, double* scale, double* trim_threshold);
// Step 3: the weighted normal equations H x = -g of the linearised residuals.
BlockSum Accumulate(const Problem& pb, const Pairs& pairs, double scale, double trim_threshold);
// Smallest over largest eigenvalue of H with the rotation rows scaled by `length` (mm).
double Conditioning(const Matrix6& H, double length);
// The spread of the pose implied by the residuals at `at` (see PoseSpread in icp_steps.cc).
void PoseSpread(const BlockSum& sum, const Eigen::Vector3d& at, double* rotation_sd_deg,
                double* translation_sd_mm);
// Step 4: the incremental pose from the solution x of the normal equations.
Rigid3 Increment(const Vector6& x, IcpMethod method);
// Step 4a: Aitken extrapolation of linearly converging steps.
Vector6 Extrapolated(const Vector6& x, const Vector6& previous, double length);

}  // namespace pectus::icp_detail
