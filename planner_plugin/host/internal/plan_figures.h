// pectus planner host: the pictures of a plan (pectus::render): the predicted chest coloured by its
// difference to the average chest, scenarios side by side on one scale, the deformed ribcage, and the
// placement search as a map of the objective over bar position and force.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "planner_plugin/host/average_chest.h"
#include "planner_plugin/host/placement_search.h"
#include "shape/core/geometry.h"
#include "shape/render/image.h"
#include "shape/render/mesh_render.h"

namespace pectus::planner {

/// A front view of the average chest's frame (looking posterior, the notch up), framing the average
/// chest, so every picture drawn with it shares position and scale.
render::View AverageChestFrontView(const AverageChest& average, int width = 560, int height = 640);

/// A view of the patient's frame (LPS) from in front, a little to the right and above, z up, framing
/// `bounds`.
render::View PatientObliqueView(const Bounds3& bounds, int width = 640, int height = 560);

/// Per-vertex colours of signed values on the diverging scale [-limit_mm, limit_mm] (NaN: grey).
Colors3 DifferenceColors(const Eigen::VectorXd& values_mm, double limit_mm);

/// `mesh` coloured by `values_mm` on [-limit_mm, limit_mm], drawn with `view`, titled.
render::Image RenderDifference(const TriangleMesh& mesh, const Eigen::VectorXd& values_mm, double limit_mm,
                               const render::View& view, const std::string& title);

/// Pictures side by side with one colour bar on [-limit_mm, limit_mm] labelled `label`.
render::Image SideBySide(const std::vector<render::Image>& pictures, double limit_mm,
                         const std::string& label);

/// The bone surface coloured by displacement magnitude on [0, limit_mm] (viridis) with its colour bar.
render::Image RenderRibcageDisplacement(const TriangleMesh& deformed_bone,
                                        const Eigen::VectorXd& displacement_mm, double limit_mm,
                                        const render::View& view, const std::string& title);

/// The search's objective over bar position (rows) and force (columns) as a coloured table with axes,
/// the best placement marked.
render::Image RenderSearchMap(const PlacementSearchResult& search, const std::string& title);

}  // namespace pectus::planner
