// pectus: other libraries' surface reconstructions, the peers pectus is measured against (CGAL and PCL
// Poisson, PCL's global RBF). Thin adaptors: Eigen in, Eigen out; the libraries only in the .cc files.
#pragma once

#include "shape/core/geometry.h"

namespace pectus {

/// PCL's Poisson reconstruction (Kazhdan et al. 2006, pcl::Poisson) of an oriented cloud.
/// @param[in] cloud  positions and unit normals pointing out of the object (mm)
/// @param[in] depth    octree depth (8 gives a 256^3 grid over the cloud's bounding cube)
/// @param[in] threads  OpenMP threads of PCL's solver (pcl::Poisson::setThreads; PCL's own default is 1);
///                     0 = omp_get_max_threads(), i.e. OMP_NUM_THREADS or every core
/// Throws Error(kBadInput) if the cloud has no normals, Error(kFailure) if PCL returns no triangles.
TriangleMesh PclPoissonSurface(const PointCloud& cloud, int depth = 8, int threads = 0);

/// PCL's MarchingCubesRBF: one global polyharmonic RBF s(x) = sum_j w_j |x - c_j|^3 interpolating 0 at the
/// points and eps at the points moved by eps along their normals (Carr et al. 2001 without the polynomial
/// part), solved densely (cost (2 n)^3: use at most a few thousand points), isosurfaced on a regular grid.
/// @param[in] cloud        positions and unit normals (mm)
/// @param[in] resolution   grid points per axis over the bounding box
/// @param[in] epsilon_mm   off-surface displacement (mm)
/// @param[in] extend       the grid extends beyond the bounding box by this fraction on every side
TriangleMesh PclMarchingCubesRbf(const PointCloud& cloud, int resolution, double epsilon_mm,
                                 double extend = 0.1);

/// CGAL's Poisson surface reconstruction (Kazhdan et al. 2006 with CGAL's Delaunay refinement and its
/// sparse solver; CGAL::poisson_surface_reconstruction_delaunay), its example's meshing criteria.
/// @param[in] cloud  positions and unit normals (mm)
/// Throws Error(kBadInput) if the cloud has no normals, Error(kFailure) if CGAL fails.
TriangleMesh CgalPoissonSurface(const PointCloud& cloud);

}  // namespace pectus
