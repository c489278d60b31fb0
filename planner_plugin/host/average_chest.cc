#include "planner_plugin/host/average_chest.h"

#include <nlohmann/json.hpp>

#include "shape/core/error.h"
#include "shape/io/landmark_io.h"
#include "shape/model/statismo_io.h"

namespace pectus::planner {

bool DetectGrid(const TriangleMesh& mesh, int* columns, int* rows) {
  if (mesh.num_faces() < 2) return false;
  const Eigen::Index m = mesh.num_vertices();
  const int c = mesh.faces(0, 1);
  if (mesh.faces(0, 0) != 0 || mesh.faces(0, 2) != 1 || c < 2 || m % c != 0) return false;
  const auto r = static_cast<int>(m / c);
  if (r < 2 || mesh.num_faces() != 2 * static_cast<Eigen::Index>(c - 1) * (r - 1)) return false;
  // Every cell as GridFaces writes it.
  Eigen::Index f = 0;
  for (int i = 0; i + 1 < r; ++i) {
    for (int j = 0; j + 1 < c; ++j, f += 2) {
      const int k00 = i * c + j, k01 = k00 + 1, k10 = k00 + c, k11 = k10 + 1;
      if (mesh.faces(f, 0) != k00 || mesh.faces(f, 1) != k10 || mesh.faces(f, 2) != k01 ||
          mesh.faces(f + 1, 0) != k01 || mesh.faces(f + 1, 1) != k10 || mesh.faces(f + 1, 2) != k11) {
        return false;
      }
    }
  }
  if (columns != nullptr) *columns = c;
  if (rows != nullptr) *rows = r;
  return true;
}

LandmarkSet GridLandmarks(const TriangleMesh& mesh, int columns, int rows) {
  const Points3& x = mesh.vertices.positions;
  auto middle_of_row = [&](int row) -> Eigen::Vector3d {
    const int a = row * columns + (columns - 1) / 2, b = row * columns + columns / 2;
    return 0.5 * (x.row(a) + x.row(b)).transpose();
  };
  LandmarkSet set;
  set.items.push_back({"sternal_notch", middle_of_row(0), "first grid row, midline"});
  set.items.push_back({"xiphoid", middle_of_row(rows - 1), "last grid row, midline"});
  return set;
}

AverageChest LoadAverageChest(const std::filesystem::path& model_path,
                              const std::filesystem::path& landmarks_file) {
  nlohmann::json info;
  const ShapeModel model = ReadStatismoModel(model_path, &info);
  AverageChest out;
  out.source = model_path.string();
  out.mesh = model.ToMesh(model.mean);
  if (out.mesh.num_faces() == 0) {
    ThrowBadInput(model_path.string(),
                  "the model has no /representer/cells: the average chest must be a mesh");
  }
  out.mesh.Validate(model_path.string());
  const bool grid = DetectGrid(out.mesh, &out.grid_columns, &out.grid_rows);
  if (!grid) out.grid_columns = out.grid_rows = 0;
  if (!landmarks_file.empty()) {
    out.landmarks = ReadLandmarks(landmarks_file);
    out.landmark_source = landmarks_file.string();
  } else if (info.is_object() && info.contains("landmarks") && info["landmarks"].is_object()) {
    for (const auto& [label, p] : info["landmarks"].items()) {
      if (!p.is_array() || p.size() != 3 || !p[0].is_number() || !p[1].is_number() || !p[2].is_number()) {
        ThrowBadInput(model_path.string(), "/pectus/info landmarks: '" + label + "' is not [x, y, z]");
      }
      out.landmarks.items.push_back(
          {label, Eigen::Vector3d(p[0].get<double>(), p[1].get<double>(), p[2].get<double>()),
           "from the model file"});
    }
    out.landmark_source = model_path.string() + " (/pectus/info landmarks)";
  } else if (grid) {
    out.landmarks = GridLandmarks(out.mesh, out.grid_columns, out.grid_rows);
    out.landmark_source = "grid convention (first and last row of the resampled grid, midline)";
  } else {
    ThrowBadInput(model_path.string(),
                  "the mean shape is not a resampled grid and the file holds no landmarks; "
                  "give them with --model-landmarks");
  }
  out.landmarks.Validate(out.landmark_source);
  for (const char* required : {"sternal_notch", "xiphoid"}) {
    if (out.landmarks.Find(required) == nullptr) {
      ThrowBadInput(out.landmark_source,
                    std::string("the average chest needs the landmark '") + required + "'");
    }
  }
  return out;
}

}  // namespace pectus::planner
