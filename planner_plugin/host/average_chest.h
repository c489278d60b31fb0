// pectus planner host: the average chest a plan is scored against: the mean shape of a statismo model
// from `pectus model build` (/model/mean over /representer/cells), with its landmarks.
#pragma once

#include <filesystem>
#include <string>

#include "shape/core/geometry.h"
#include "shape/core/landmarks.h"

namespace pectus::planner {

/// The reference chest.
struct AverageChest {
  std::string source;                   ///< the model file
  TriangleMesh mesh;                    ///< the model's mean shape, mm, faces outward (anterior)
  LandmarkSet landmarks;                ///< at least sternal_notch and xiphoid
  std::string landmark_source;          ///< where the landmarks came from (for the report)
  int grid_columns = 0, grid_rows = 0;  ///< the grid of `pectus resample` (0 if the mesh is not one)
};

/// Recognises a grid mesh of `pectus resample` (GridFaces: rows along the sternal line, columns across
/// the chest, two triangles per cell starting (0, columns, 1)). Returns false if `mesh` is not one.
bool DetectGrid(const TriangleMesh& mesh, int* columns, int* rows);

/// Landmarks of a resampled grid with the default region of interest (no margins): the sternal notch
/// at the middle of the first row, the xiphoid at the middle of the last (ChestRoi,
/// shape/model/compute_chest_roi.h).
LandmarkSet GridLandmarks(const TriangleMesh& mesh, int columns, int rows);

/// Reads the average chest from a statismo model file. Landmarks, in order of preference: the file
/// `landmarks_file` (any format ReadLandmarks reads) if given; a "landmarks" object in the model's
/// /pectus/info ({label: [x, y, z]}); the grid convention of GridLandmarks. Throws Error(kBadInput)
/// naming the file for a model without faces or without usable landmarks.
AverageChest LoadAverageChest(const std::filesystem::path& model,
                              const std::filesystem::path& landmarks_file = {});

}  // namespace pectus::planner
