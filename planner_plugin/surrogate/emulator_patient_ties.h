// pectus planner: how a patient's skin and sternal lift follow the boundary nodes of its ribcage mesh, for
// the response emulator (issue 14). The mesh's boundary nodes are the same nodes of the generic ribcage in
// every patient, so the emulator learns their responses across patients; a skin vertex of the grid, by
// contrast, is tied to whichever bone nodes lie under its ray in that patient (SkinSurface::ties), and the
// sternal lift is read at that patient's slice of deepest depression (SternumLiftTiesOf). Both are linear
// in the nodes' displacements and known from the fitted ribcage alone, without a finite element run: a
// prediction of the nodes gives the patient's skin and lift exactly as the FE model would map them.
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <cstdint>
#include <vector>

#include "planner_plugin/ribcage/build_skin_surface.h"
#include "planner_plugin/ribcage/patient_ribcage.h"
#include "planner_plugin/surrogate/response_emulator.h"

namespace pectus::planner {

/// One patient's outputs as linear functionals of the boundary nodes' displacements.
struct EmulatorPatientTies {
  /// #skin vertices by #boundary nodes, rows summing to 1: a skin vertex's displacement (x, y, z each) is
  /// its row times the nodes' displacements.
  Eigen::SparseMatrix<double, Eigen::RowMajor> skin;
  /// 1 by 3 #boundary nodes (node after node, x, y, z): the sternal lift (mm) of a nodal displacement.
  Eigen::SparseMatrix<double, Eigen::RowMajor> lift;
};

/// The ties of `ribcage` (its skin `skin`, built by BuildSkinSurface) to `boundary_nodes` (mesh nodes,
/// ExtractBoundary(ribcage.mesh).nodes or any set holding every node the skin and lift are tied to).
/// Throws Error(kFailure) naming the patient if a tie reaches a node outside `boundary_nodes`.
EmulatorPatientTies MakeEmulatorPatientTies(const PatientRibcage& ribcage, const SkinSurface& skin,
                                            const std::vector<std::int32_t>& boundary_nodes);

/// A prediction of the boundary nodes (per position 3 #boundary nodes) carried through `ties`: per
/// position the skin (3 #skin vertices, mm/N) and the lift (mm/N). Standard deviations are carried as the
/// ties' weighted sums of the nodes' (|w| sd), as if the errors of a vertex's nodes were fully correlated
/// (they are neighbours): an upper bound of the carried deviation. Throws Error(kUsage) for a prediction
/// of another size.
ResponseEmulatorPrediction ThroughTies(const ResponseEmulatorPrediction& nodes,
                                       const EmulatorPatientTies& ties);

}  // namespace pectus::planner
