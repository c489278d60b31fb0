// pectus: the pictures of the analyst's results (colour maps on a surface, histograms, variance explained,
// mode displacements, model quality curves), drawn with pectus::render. Every figure exists as an Image
// (for the pipeline's HTML report) and as a Write...Png that writes it atomically.
#pragma once

#include <Eigen/Core>
#include <filesystem>
#include <string>

#include "shape/core/geometry.h"
#include "shape/model/model_quality.h"
#include "shape/model/shape_model.h"
#include "shape/render/colormap.h"
#include "shape/render/image.h"

namespace pectus {

/// Colours of `values` on the fixed scale [lo, hi]: blue-white-red when the scale straddles zero (signed
/// values), viridis otherwise. #values by 3.
Colors3 ColorsForValues(const Eigen::VectorXd& values, double lo, double hi);

/// A colour map on a surface, seen from the front, with a colour bar. Two figures with the same min and
/// max share one scale.
struct SurfaceMapFigure {
  std::string title;         ///< above the picture
  std::string label = "mm";  ///< colour bar label
  double min = -1.0;         ///< colour scale (values outside are clamped)
  double max = 1.0;
  Eigen::Vector3d up =
      Eigen::Vector3d::Zero();  ///< shown upward; zero: the notch-up axis guessed from the mesh
  int size = 640;               ///< picture height in pixels (the colour bar matches)
};

/// The picture: `mesh` coloured by `values` (#vertices) seen from `anterior` (the direction the front of
/// the chest faces; zero: the mesh's mean normal). Throws Error(kUsage) if the sizes disagree.
render::Image SurfaceMapImage(const TriangleMesh& mesh, const Eigen::VectorXd& values,
                              const Eigen::Vector3d& anterior, const SurfaceMapFigure& figure);
/// SurfaceMapImage written as a PNG.
void WriteSurfaceMapPng(const std::filesystem::path& path, const TriangleMesh& mesh,
                        const Eigen::VectorXd& values, const Eigen::Vector3d& anterior,
                        const SurfaceMapFigure& figure);

/// A histogram of `values` (mm) over [lo, hi] in 40 bins.
render::Image HistogramImage(const Eigen::VectorXd& values, const std::string& label, double lo, double hi);
void WriteHistogramPng(const std::filesystem::path& path, const Eigen::VectorXd& values,
                       const std::string& label, double lo, double hi);

/// Bars of the variance explained by each mode (up to 20) with the cumulative curve over them, in %.
render::Image VarianceExplainedImage(const ShapeModel& model);
void WriteVarianceExplainedPng(const std::filesystem::path& path, const ShapeModel& model);

/// Mode `mode` (1-based) at +sd standard deviations: the displacement from the mean along the mean's
/// normals (mm) as a colour map on the mean shape, symmetric scale.
render::Image ModeDisplacementImage(const ShapeModel& model, int mode, double sd);
void WriteModeDisplacementPng(const std::filesystem::path& path, const ShapeModel& model, int mode,
                              double sd);

/// Compactness, generalization and specificity against the number of modes, side by side, each with
/// +-1 standard error dashed.
render::Image QualityCurvesImage(const ModelQualityCurves& curves);
void WriteQualityCurvesPng(const std::filesystem::path& path, const ModelQualityCurves& curves);

/// Per-vertex normals of a mesh (area weighted, unit; zero for a vertex without faces), #vertices by 3.
Points3 AreaWeightedNormals(const TriangleMesh& mesh);

/// The signed displacement of `moved` from `mesh` along the normals of `mesh` (same vertex count), mm.
Eigen::VectorXd NormalDisplacement(const TriangleMesh& mesh, const Points3& moved);

}  // namespace pectus
