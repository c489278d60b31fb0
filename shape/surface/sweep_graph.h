// pectus: the graph of overlapping sweeps that MergeSweeps works on: one side for every sweep's normals,
// which pairs overlap, their correspondences, and poses along a spanning tree of the pairs.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "shape/core/geometry.h"
#include "shape/surface/sweep_surface.h"

namespace pectus {

/// Two overlapping sweeps.
struct SweepLink {
  std::size_t i = 0, j = 0;  ///< the sweeps, i < j
  double overlap = 0.0;      ///< fraction of the smaller sweep's samples that lie on the other
};

/// Turns every sweep's normals to one side: sweeps join the oriented set in order of their overlap with
/// it, each taking the side most of its overlapping samples agree on; then the whole set faces away from
/// its centroid (outward for a closed object, toward the scanner for a chest).
/// @param[in]     P            T_world_sweep of each sweep
/// @param[in]     distance_mm  samples farther than this from the other sweep do not vote
/// @param[in]     anchor       the sweep whose side the others follow
/// @param[in,out] sweeps       their normals flipped where needed
void OrientSweeps(const std::vector<Rigid3>& P, double distance_mm, std::size_t anchor,
                  std::vector<SweepSurface>* sweeps);

/// Every pair overlapping by at least min_fraction of the smaller sweep's samples: samples with a point of
/// the other sweep within distance_mm facing the same way (normals within 45 degrees) that is not on its
/// border, or is but with the sample within edge_mm of it along its tangent plane (< 0: one point spacing
/// of that sweep, so that a sample beyond its edge does not count; the tracker's expected error at the
/// starting poses, where a sweep slid off by the tracker still shares what it shares at the truth).
std::vector<SweepLink> FindSweepLinks(const std::vector<SweepSurface>& S, const std::vector<Rigid3>& P,
                                      double distance_mm, double min_fraction, double edge_mm = -1.0);

/// The smallest distance (mm) from a sample of sweep s to any point of another sweep at the poses P, and
/// which sweep that is (*nearest; s itself when there is no other sweep).
double DistanceToNearestSweep(const std::vector<SweepSurface>& S, const std::vector<Rigid3>& P, std::size_t s,
                              std::size_t* nearest);

/// Correspondences of every link in both directions, at most per_pair each way, gated at gate_mm.
std::vector<SweepCorrespondence> AllCorrespondences(const std::vector<SweepSurface>& S,
                                                    const std::vector<Rigid3>& P,
                                                    const std::vector<SweepLink>& links, int per_pair,
                                                    double gate_mm);

/// Every row of a link's source sweep (not only its subsample) with a point of its target within gate_mm
/// at the poses P: the candidates of the correspondences with every point. Two lists per link, in
/// AllCorrespondences's order: [2k] rows of links[k].j near links[k].i, [2k + 1] rows of i near j.
std::vector<std::vector<std::uint32_t>> OverlapRows(const std::vector<SweepSurface>& S,
                                                    const std::vector<Rigid3>& P,
                                                    const std::vector<SweepLink>& links, double gate_mm);

/// Correspondences of every link in both directions from the given rows (OverlapRows), each row once
/// (no cap), gated at gate_mm.
std::vector<SweepCorrespondence> AllCorrespondences(const std::vector<SweepSurface>& S,
                                                    const std::vector<Rigid3>& P,
                                                    const std::vector<SweepLink>& links,
                                                    const std::vector<std::vector<std::uint32_t>>& rows,
                                                    double gate_mm);

/// Poses from a maximum spanning tree (by overlap) of the links whose pairwise registration succeeded
/// (ok[k]; T_i_j[k] the pose of sweep j in sweep i), grown from the anchor, whose pose is kept.
void PosesFromTree(const std::vector<SweepLink>& links, const std::vector<Rigid3>& T_i_j,
                   const std::vector<bool>& ok, std::size_t anchor, std::vector<Rigid3>* P);

}  // namespace pectus
