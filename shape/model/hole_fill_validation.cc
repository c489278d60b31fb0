#include "shape/model/hole_fill_validation.h"

#include <cmath>
#include <sstream>

#include "shape/core/error.h"

namespace pectus {
namespace {

bool InsideAny(double u, double v, const std::vector<RemovedDisk>& disks) {
  for (const RemovedDisk& d : disks) {
    if ((u - d.u) * (u - d.u) + (v - d.v) * (v - d.v) <= d.radius_mm * d.radius_mm) return true;
  }
  return false;
}

}  // namespace

std::vector<RemovedDisk> DefaultRemovedDisks(const ChestRoi& roi, double radius_mm) {
  return {{0.5 * (roi.u_min + roi.u_max), 0.5 * (roi.v_min + roi.v_max), radius_mm},
          {roi.u_min, roi.v_min + roi.height() / 3.0, radius_mm},
          {roi.u_max, roi.v_max, radius_mm}};
}

TriangleMesh RemoveDisks(const TriangleMesh& surface, const ChestRoi& roi,
                         const std::vector<RemovedDisk>& disks) {
  const Points3 uvw = roi.ToRoi(surface.vertices.positions);
  const Eigen::Index n = surface.num_vertices();
  std::vector<bool> removed(static_cast<std::size_t>(n));
  for (Eigen::Index k = 0; k < n; ++k) removed[k] = InsideAny(uvw(k, 0), uvw(k, 1), disks);
  std::vector<bool> keep(static_cast<std::size_t>(n), surface.num_faces() == 0);
  std::vector<Eigen::Index> kept_faces;
  if (surface.num_faces() > 0) {
    for (Eigen::Index f = 0; f < surface.num_faces(); ++f) {
      if (removed[surface.faces(f, 0)] || removed[surface.faces(f, 1)] || removed[surface.faces(f, 2)])
        continue;
      kept_faces.push_back(f);
      for (int c = 0; c < 3; ++c) keep[surface.faces(f, c)] = true;
    }
  } else {
    for (Eigen::Index k = 0; k < n; ++k) keep[k] = !removed[k];
  }
  // Renumber the kept vertices and copy their attributes.
  std::vector<std::int32_t> new_index(static_cast<std::size_t>(n), -1);
  std::vector<Eigen::Index> old_index;
  for (Eigen::Index k = 0; k < n; ++k) {
    if (keep[k]) {
      new_index[k] = static_cast<std::int32_t>(old_index.size());
      old_index.push_back(k);
    }
  }
  const auto m = static_cast<Eigen::Index>(old_index.size());
  TriangleMesh out;
  const PointCloud& in = surface.vertices;
  out.vertices.positions.resize(m, 3);
  if (in.has_normals()) out.vertices.normals.resize(m, 3);
  if (in.has_colors()) out.vertices.colors.resize(m, 3);
  for (const auto& [name, values] : in.scalars) out.vertices.scalars[name].resize(m);
  for (Eigen::Index k = 0; k < m; ++k) {
    const Eigen::Index o = old_index[k];
    out.vertices.positions.row(k) = in.positions.row(o);
    if (in.has_normals()) out.vertices.normals.row(k) = in.normals.row(o);
    if (in.has_colors()) out.vertices.colors.row(k) = in.colors.row(o);
    for (const auto& [name, values] : in.scalars) out.vertices.scalars[name][k] = values[o];
  }
  out.faces.resize(static_cast<Eigen::Index>(kept_faces.size()), 3);
  for (std::size_t f = 0; f < kept_faces.size(); ++f) {
    for (int c = 0; c < 3; ++c)
      out.faces(static_cast<Eigen::Index>(f), c) = new_index[surface.faces(kept_faces[f], c)];
  }
  return out;
}

HoleFillResult ValidateHoleFill(const TriangleMesh& surface, const ChestRoi& roi,
                                const std::vector<RemovedDisk>& disks, const CrossSectionOptions& options,
                                const std::string& what) {
  if (disks.empty()) ThrowUsage("hole-fill validation needs at least one region to remove");
  for (const RemovedDisk& d : disks) {
    if (!(d.radius_mm > 0.0) || !std::isfinite(d.radius_mm) || !std::isfinite(d.u) || !std::isfinite(d.v)) {
      ThrowUsage("a removed region needs a finite centre and a radius > 0 mm");
    }
  }
  HoleFillResult result;
  result.full = ResampleCrossSections(surface, roi, options, what);
  result.holed_surface = RemoveDisks(surface, roi, disks);
  result.holed = ResampleCrossSections(result.holed_surface, roi, options, what + " with regions removed");

  const Eigen::VectorXd& a = result.holed.mesh.vertices.scalars.at("depth_mm");
  const Eigen::VectorXd& b = result.full.mesh.vertices.scalars.at("depth_mm");
  result.error_mm = a - b;
  const Eigen::VectorXd u = GridLateralPositions(roi, options.grid);
  const Eigen::VectorXd v = GridSternalPositions(roi, options.grid);
  result.in_disk = Eigen::VectorXi::Zero(result.error_mm.size());
  double sum_in = 0.0;
  for (int i = 0; i < options.grid.sternal; ++i) {
    for (int j = 0; j < options.grid.lateral; ++j) {
      const Eigen::Index k = options.grid.Index(i, j);
      if (!InsideAny(u[j], v[i], disks)) continue;
      result.in_disk[k] = 1;
      ++result.vertices_in_disks;
      result.max_error_in_disks_mm = std::max(result.max_error_in_disks_mm, std::abs(result.error_mm[k]));
      sum_in += result.error_mm[k] * result.error_mm[k];
    }
  }
  result.rms_error_in_disks_mm =
      result.vertices_in_disks > 0 ? std::sqrt(sum_in / static_cast<double>(result.vertices_in_disks)) : 0.0;
  result.max_error_mm = result.error_mm.cwiseAbs().maxCoeff();
  result.rms_error_mm =
      std::sqrt(result.error_mm.squaredNorm() / static_cast<double>(result.error_mm.size()));
  std::ostringstream msg;
  msg << disks.size() << " regions removed (" << result.vertices_in_disks << " grid vertices): max error "
      << result.max_error_in_disks_mm << " mm, RMS " << result.rms_error_in_disks_mm << " mm inside; max "
      << result.max_error_mm << " mm over the grid";
  result.message = msg.str();
  return result;
}

}  // namespace pectus
