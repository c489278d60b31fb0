// Test helper: a statismo model file whose mean is a given mesh (two training shapes 1 mm apart along z),
// the average chest a plan is scored against.
#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>

#include "shape/core/geometry.h"
#include "shape/model/shape_model.h"
#include "shape/model/statismo_io.h"

namespace pectus::planner::testing {

/// Writes the model to `path`; `info` goes into the file's metadata (e.g. {"landmarks": {...}}).
inline void WriteAverageModel(const std::filesystem::path& path, const TriangleMesh& mean,
                              const nlohmann::json& info = nlohmann::json::object()) {
  Eigen::MatrixXd shapes(2, 3 * mean.num_vertices());
  Points3 a = mean.vertices.positions, b = mean.vertices.positions;
  a.col(2).array() += 0.5;
  b.col(2).array() -= 0.5;
  shapes.row(0) = Eigen::Map<const Eigen::VectorXd>(a.data(), a.size()).transpose();
  shapes.row(1) = Eigen::Map<const Eigen::VectorXd>(b.data(), b.size()).transpose();
  ShapeModel model = BuildShapeModel(shapes);
  model.faces = mean.faces;
  WriteStatismoModel(path, model, info);
}

}  // namespace pectus::planner::testing
