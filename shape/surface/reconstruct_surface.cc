#include "shape/surface/reconstruct_surface.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <sstream>

#include "registration/kdtree.h"
#include "shape/core/error.h"
#include "shape/core/number_format.h"
#include "shape/core/per_vertex_normals.h"
#include "shape/surface/extract_isosurface.h"
#include "shape/surface/internal/cloud_scales.h"
#include "shape/surface/rbf_levels.h"
#include "shape/surface/surface_normals.h"

namespace pectus {
namespace {

constexpr Eigen::Index kMinPoints = 16;
// Default centre spacing: at least this many point spacings (so that a centre averages several points
// of a sparse cloud) and this many noise levels (so that it averages the noise of a dense one).
constexpr double kCentrePointSpacings = 4.0;
constexpr double kCentreNoiseLevels = 22.0;

class StageClock {
 public:
  explicit StageClock(Timings* out) : out_(out) {}
  void Lap(const std::string& stage) {
    const auto now = std::chrono::steady_clock::now();
    out_->Add(stage, std::chrono::duration<double>(now - last_).count());
    last_ = now;
  }

 private:
  Timings* out_;
  std::chrono::steady_clock::time_point last_ = std::chrono::steady_clock::now();
};

// Rejects clouds that cannot bound a surface: all points on a line or at one place.
void CheckNotDegenerate(const Points3& p, const std::string& what) {
  const Eigen::RowVector3d mean = p.colwise().mean();
  const Eigen::Matrix3d cov = (p.rowwise() - mean).transpose() * (p.rowwise() - mean) / double(p.rows());
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov, Eigen::EigenvaluesOnly);
  const Eigen::Vector3d l = eig.eigenvalues();  // ascending
  if (!(l(2) > 0.0)) ThrowBadInput(what, "all " + std::to_string(p.rows()) + " points are at the same place");
  if (l(1) <= 1e-10 * l(2)) {
    ThrowBadInput(what, "all " + std::to_string(p.rows()) +
                            " points lie on one line; a surface needs points spread in two directions");
  }
}

}  // namespace

bool ReconstructOptions::IsValid(std::string* why) const {
  auto fail = [&](const std::string& text) {
    if (why) *why = text;
    return false;
  };
  auto non_negative = [](double v) { return v >= 0.0 && std::isfinite(v); };
  if (!non_negative(spacing_mm)) return fail("spacing must be >= 0 mm (0 = automatic)");
  if (target_faces < 0) return fail("target faces must be >= 0");
  if (!non_negative(detail_mm)) return fail("detail must be >= 0 mm (0 = automatic)");
  if (!non_negative(smoothing)) return fail("smoothing must be >= 0");
  if (!non_negative(fill_holes_mm)) return fail("fill-holes size must be >= 0 mm");
  if (!non_negative(margin_mm)) return fail("margin must be >= 0 mm (0 = automatic)");
  if (!non_negative(off_surface_distance_mm))
    return fail("off-surface distance must be >= 0 mm (0 = automatic)");
  if (normal_neighbours < 3 || normal_neighbours > 256) return fail("normal neighbours must be in [3, 256]");
  if (viewpoint && !viewpoint->allFinite()) return fail("viewpoint must be finite");
  return true;
}

ReconstructResult ReconstructSurface(const PointCloud& cloud, const ReconstructOptions& options,
                                     const std::string& what) {
  std::string why;
  if (!options.IsValid(&why)) ThrowUsage("reconstruct: " + why);
  ReconstructResult result;
  StageClock clock(&result.timings_s);

  // 1. Check the input.
  cloud.Validate(what);
  result.input_points = cloud.size();
  if (cloud.size() < kMinPoints) {
    ThrowBadInput(what, "has " + std::to_string(cloud.size()) + " points; a surface needs at least " +
                            std::to_string(kMinPoints));
  }
  CheckNotDegenerate(cloud.positions, what);
  result.point_spacing_mm = PointSpacing(cloud.positions);
  if (!(result.point_spacing_mm > 0.0)) {
    ThrowBadInput(what, "has no two distinct points among the neighbours sampled (all duplicates?)");
  }

  // 2. Scales: grid step, centre spacing (the finest detail followed), cell size, off-surface distance.
  // The detail follows the grid step and the noise, not the density: a surface needs the same
  // resolution however many points sample it, and noisier points need larger centres to average over.
  const double s = result.point_spacing_mm;
  result.noise_mm = NoiseLevel(cloud.positions, s);
  double h = options.spacing_mm;
  if (h == 0.0 && options.target_faces > 0) {
    // Marching cubes gives about 2.2 triangles per h^2 of area; the area is about points * s^2.
    h = std::sqrt(2.2 * double(cloud.size()) * s * s / double(options.target_faces));
  }
  if (h == 0.0) h = 1.5 * s;
  const double detail =
      options.detail_mm > 0.0
          ? options.detail_mm
          : std::max({2.0 * h, kCentrePointSpacings * s, kCentreNoiseLevels * result.noise_mm});
  result.spacing_mm = h;
  result.centre_spacing_mm = detail;

  // 3. The working cloud: a cloud denser than a quarter of the detail is averaged per cube of that side
  // first (O(N); it also averages the noise), so that everything after costs what the detail needs, not
  // what the density gives. The points of each cube are averaged apart on the two sides of a thin sheet
  // when normals are given.
  const double cube = 0.25 * detail;
  const bool keep_normals = cloud.has_normals() && !options.recompute_normals;
  PointCloud working;
  Eigen::VectorXd counts;
  if (s < cube) {
    RbfLevel averaged;
    AverageByVoxel(cloud.positions, keep_normals ? cloud.normals : Points3(0, 3),
                   Eigen::VectorXd::Ones(cloud.size()), cube, &averaged);
    working.positions = std::move(averaged.positions);
    working.normals = std::move(averaged.normals);
    counts = std::move(averaged.counts);
  } else {
    working.positions = cloud.positions;
    if (keep_normals) working.normals = cloud.normals;
    counts = Eigen::VectorXd::Ones(cloud.size());
  }
  const KdTree3 tree(working.positions);  // refers to working.positions, which stays unchanged from here
  result.working_points = working.size();

  // 4. Oriented normals: given, toward the scanner, or by propagation (Hoppe et al. 1992).
  SurfaceNormalOptions no;
  no.neighbours = options.normal_neighbours;
  no.recompute = options.recompute_normals;
  no.viewpoint = options.viewpoint;
  const SurfaceNormalResult normals = SurfaceNormals(working, tree, no, what);
  result.normals_source = normals.source;
  std::vector<Eigen::Index> usable;
  usable.reserve(std::size_t(normals.usable));
  for (Eigen::Index i = 0; i < normals.normals.rows(); ++i) {
    if (normals.normals.row(i).squaredNorm() > 0.25) usable.push_back(i);
  }
  const Points3 positions = working.positions(usable, Eigen::all);
  const Points3 oriented = normals.normals(usable, Eigen::all);
  const Eigen::VectorXd weights = counts(usable);
  result.used_points = positions.rows();
  clock.Lap("normals");

  RbfImplicitOptions ro;
  ro.centre_spacing_mm = detail;
  ro.cell_size_mm = 2.0 * detail;
  ro.off_surface_distance_mm =
      options.off_surface_distance_mm > 0.0 ? options.off_surface_distance_mm : 0.5 * detail;
  ro.smoothing = options.smoothing;
  ro.max_fill_distance_mm = 0.5 * options.fill_holes_mm + ro.cell_size_mm;
  ro.max_hole_size_mm = options.fill_holes_mm;
  result.cell_size_mm = ro.cell_size_mm;

  // 5. The implicit s(x), fitted lazily where marching cubes asks for it.
  RbfImplicit implicit(positions, oriented, weights, ro);
  clock.Lap("centres");
  MarchingCubesOptions mo;
  mo.spacing_mm = h;
  mo.origin = ComputeBounds(positions).min;
  MarchingCubesResult mc = ExtractIsosurface(
      [&](const Points3& q, Eigen::VectorXd* v) { implicit.Evaluate(q, v); }, implicit.Seeds(), mo);
  if (mc.reached_limit) {
    ThrowFailure("reconstruct: the surface grew beyond " + std::to_string(mo.max_cubes) +
                     " cubes; use a larger --spacing",
                 what);
  }
  result.cells = implicit.num_cells();
  result.surface_cubes = mc.surface_cubes;
  clock.Lap("fit_and_isosurface");

  // 6. Trim to the scanned region, keeping hole fillings.
  TrimOptions to;
  to.margin_mm = options.margin_mm > 0.0 ? options.margin_mm : detail;
  to.max_hole_size_mm = options.fill_holes_mm;
  result.trim = TrimToData(tree, &mc.mesh, to);
  result.mesh = std::move(mc.mesh);
  if (result.mesh.num_faces() == 0) {
    ThrowFailure("reconstruct: no surface was found near the data (normals inconsistent?)", what);
  }
  result.mesh.vertices.normals =
      PerVertexNormals(result.mesh.vertices.positions, result.mesh.faces, Eigen::RowVector3d(0.0, 0.0, 1.0));
  clock.Lap("trim");

  // 7. Fitting accuracy (dissertation Eq. 11) and the CGAL check.
  result.accuracy = implicit.FittingAccuracy();
  clock.Lap("fitting_accuracy");
  if (options.check) {
    result.check = CheckMesh(result.mesh);
    clock.Lap("check");
  }
  // The summary: the surface's size and how far the fit's on-surface points are from it (RMS and 95th
  // percentile). Carr's maximum residual stays in `accuracy`: it is set by the points the fit rejects as
  // outliers and reads as an error it is not.
  std::ostringstream msg;
  msg << result.mesh.num_vertices() << " vertices, " << result.mesh.num_faces() << " triangles from "
      << result.used_points << " points; " << result.trim.holes_filled << " holes filled"
      << (result.trim.boundary_edges == 0 ? ", watertight" : "") << "; on-surface residual RMS "
      << FormatMm(result.accuracy.on_surface_rms_mm) << ", p95 "
      << FormatMm(result.accuracy.on_surface_p95_mm);
  result.message = msg.str();
  return result;
}

std::string ReconstructResult::BriefReport() const {
  return message + "; " + FormatSignificant(timings_s.Total()) + " s";
}

}  // namespace pectus
