#include "shape/model/shape_grid.h"

#include <limits>
#include <regex>

#include "shape/core/error.h"

namespace pectus {

bool GridSize::IsValid(std::string* why) const {
  if (lateral < 2 || sternal < 2 || lateral > 100000 || sternal > 100000 ||
      num_vertices() > std::numeric_limits<std::int32_t>::max() / 4) {
    if (why != nullptr) {
      *why = "grid size " + std::to_string(lateral) + "x" + std::to_string(sternal) +
             " is out of range (each count in [2, 100000])";
    }
    return false;
  }
  return true;
}

GridSize ParseGridSize(const std::string& text) {
  static const std::regex pattern(R"(\s*(\d+)\s*[xX]\s*(\d+)\s*)");
  std::smatch m;
  if (!std::regex_match(text, m, pattern) || m[1].length() > 6 || m[2].length() > 6) {
    ThrowUsage("grid size '" + text + "' is not LATERALxSTERNAL, e.g. 51x101");
  }
  GridSize size{std::stoi(m[1]), std::stoi(m[2])};
  std::string why;
  if (!size.IsValid(&why)) ThrowUsage(why);
  return size;
}

Eigen::VectorXd GridLateralPositions(const ChestRoi& roi, const GridSize& size) {
  return Eigen::VectorXd::LinSpaced(size.lateral, roi.u_min, roi.u_max);
}

Eigen::VectorXd GridSternalPositions(const ChestRoi& roi, const GridSize& size) {
  return Eigen::VectorXd::LinSpaced(size.sternal, roi.v_min, roi.v_max);
}

Faces3 GridFaces(const GridSize& size) {
  Faces3 faces(2 * static_cast<Eigen::Index>(size.lateral - 1) * (size.sternal - 1), 3);
  Eigen::Index f = 0;
  for (int i = 0; i + 1 < size.sternal; ++i) {
    for (int j = 0; j + 1 < size.lateral; ++j) {
      const auto k00 = static_cast<std::int32_t>(size.Index(i, j));
      const auto k01 = static_cast<std::int32_t>(size.Index(i, j + 1));
      const auto k10 = static_cast<std::int32_t>(size.Index(i + 1, j));
      const auto k11 = static_cast<std::int32_t>(size.Index(i + 1, j + 1));
      // lateral x sternal = -normal, so (u, v)-clockwise winding faces anterior.
      faces.row(f++) << k00, k10, k01;
      faces.row(f++) << k01, k10, k11;
    }
  }
  return faces;
}

Eigen::VectorXd ToShapeVector(const Points3& vertices) {
  return Eigen::Map<const Eigen::VectorXd>(vertices.data(), vertices.size());
}

Points3 FromShapeVector(const Eigen::VectorXd& shape) {
  if (shape.size() % 3 != 0) {
    ThrowBadInput("shape vector", "has " + std::to_string(shape.size()) + " numbers, not a multiple of 3");
  }
  return Eigen::Map<const Points3>(shape.data(), shape.size() / 3, 3);
}

}  // namespace pectus
