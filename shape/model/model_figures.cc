#include "shape/model/model_figures.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <vector>

#include "shape/core/error.h"
#include "shape/model/shape_grid.h"
#include "shape/render/mesh_render.h"
#include "shape/render/plot.h"

namespace pectus {
namespace {

using render::Image;

// Unit vector of `v` with its component along `axis` removed; zero if nothing is left.
Eigen::Vector3d Perpendicular(const Eigen::Vector3d& v, const Eigen::Vector3d& axis) {
  const Eigen::Vector3d p = v - v.dot(axis) * axis;
  return p.norm() > 1e-6 * std::max(1.0, v.norm()) ? Eigen::Vector3d(p.normalized())
                                                   : Eigen::Vector3d::Zero();
}

// The long axis of the points across the view (a chest grid is longer along the sternum), pointing from
// the centroid toward vertex 0 (the notch of a grid from `pectus resample`).
Eigen::Vector3d NotchUpAxis(const Points3& points, const Eigen::Vector3d& forward) {
  const Eigen::RowVector3d centroid = points.colwise().mean();
  const Eigen::MatrixXd centred = points.rowwise() - centroid;
  const Eigen::Matrix3d P = Eigen::Matrix3d::Identity() - forward * forward.transpose();
  const Eigen::Matrix3d C = P * (centred.transpose() * centred) * P;
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(C);
  Eigen::Vector3d up = eig.eigenvectors().col(2);
  if ((points.row(0) - centroid).dot(up.transpose()) < 0.0) up = -up;
  return up;
}

// The mean normal of a mesh (area weighted), unit; +z if it has no area.
Eigen::Vector3d MeanNormal(const TriangleMesh& mesh) {
  Eigen::Vector3d n = Eigen::Vector3d::Zero();
  const Points3& x = mesh.vertices.positions;
  for (Eigen::Index f = 0; f < mesh.num_faces(); ++f) {
    const Eigen::Vector3d a = x.row(mesh.faces(f, 0)), b = x.row(mesh.faces(f, 1)),
                          c = x.row(mesh.faces(f, 2));
    n += (b - a).cross(c - a);
  }
  return n.norm() > 0.0 ? Eigen::Vector3d(n.normalized()) : Eigen::Vector3d::UnitZ();
}

std::vector<double> ToStd(const Eigen::VectorXd& v) {
  return std::vector<double>(v.data(), v.data() + v.size());
}

}  // namespace

Colors3 ColorsForValues(const Eigen::VectorXd& values, double lo, double hi) {
  const render::Colormap map =
      lo < 0.0 && hi > 0.0 ? render::Colormap::kDiverging : render::Colormap::kViridis;
  return render::MapColors(values, lo, hi, map);
}

Image SurfaceMapImage(const TriangleMesh& mesh, const Eigen::VectorXd& values,
                      const Eigen::Vector3d& anterior, const SurfaceMapFigure& figure) {
  if (values.size() != mesh.num_vertices()) {
    ThrowUsage("a surface map needs one value per vertex: " + std::to_string(values.size()) + " values for " +
               std::to_string(mesh.num_vertices()) + " vertices");
  }
  const Eigen::Vector3d front =
      anterior.norm() > 0.0 ? Eigen::Vector3d(anterior.normalized()) : MeanNormal(mesh);
  render::View view = render::View::Front(figure.size, figure.size);
  view.direction = -front;
  Eigen::Vector3d up = Perpendicular(figure.up, front);
  if (up.isZero())
    up = mesh.num_vertices() > 2 ? NotchUpAxis(mesh.vertices.positions, front)
                                 : Perpendicular(Eigen::Vector3d::UnitY(), front);
  if (up.isZero()) up = Perpendicular(Eigen::Vector3d::UnitX(), front);
  view.up = up;
  const Colors3 colours = ColorsForValues(values, figure.min, figure.max);
  const Image picture = render::RenderMesh(mesh, view, &colours);
  const render::Colormap map =
      figure.min < 0.0 && figure.max > 0.0 ? render::Colormap::kDiverging : render::Colormap::kViridis;
  const Image bar = render::ColorBar(figure.min, figure.max, map, figure.label, figure.size);
  const Image both = render::HStack({picture, bar}, 8);
  return figure.title.empty() ? both : render::WithTitle(both, figure.title);
}

void WriteSurfaceMapPng(const std::filesystem::path& path, const TriangleMesh& mesh,
                        const Eigen::VectorXd& values, const Eigen::Vector3d& anterior,
                        const SurfaceMapFigure& figure) {
  render::WritePng(SurfaceMapImage(mesh, values, anterior, figure), path);
}

Image HistogramImage(const Eigen::VectorXd& values, const std::string& label, double lo, double hi) {
  render::PlotOptions o;
  o.title = "distribution of " + label;
  o.x_label = label;
  o.y_label = "vertices";
  return render::PlotHistogram(ToStd(values), 40, o, lo, hi);
}

void WriteHistogramPng(const std::filesystem::path& path, const Eigen::VectorXd& values,
                       const std::string& label, double lo, double hi) {
  render::WritePng(HistogramImage(values, label, lo, hi), path);
}

Image VarianceExplainedImage(const ShapeModel& model) {
  const int k = std::min(20, model.num_modes());
  std::vector<std::string> labels;
  std::vector<double> bars;
  render::Series cumulative;
  cumulative.label = "cumulative";
  cumulative.colour = {214, 39, 40};
  const Eigen::VectorXd f = model.ExplainedFraction(), c = model.CumulativeFraction();
  for (int j = 0; j < k; ++j) {
    labels.push_back(std::to_string(j + 1));
    bars.push_back(100.0 * f[j]);
    cumulative.x.push_back(j + 1);  // bar j + 1 stands at x = j + 1
    cumulative.y.push_back(100.0 * c[j]);
  }
  render::PlotOptions o;
  o.title = "variance explained: per mode (bars), cumulative (line)";
  o.x_label = "mode";
  o.y_label = "%";
  o.y_min = 0.0;
  o.y_max = 100.0;
  return render::PlotBars(labels, bars, o, {cumulative});
}

void WriteVarianceExplainedPng(const std::filesystem::path& path, const ShapeModel& model) {
  render::WritePng(VarianceExplainedImage(model), path);
}

Points3 AreaWeightedNormals(const TriangleMesh& mesh) {
  const Points3& x = mesh.vertices.positions;
  Points3 n = Points3::Zero(x.rows(), 3);
  for (Eigen::Index f = 0; f < mesh.num_faces(); ++f) {
    const Eigen::RowVector3d a = x.row(mesh.faces(f, 0)), b = x.row(mesh.faces(f, 1)),
                             c = x.row(mesh.faces(f, 2));
    const Eigen::RowVector3d fn = (b - a).cross(c - a);
    for (int v = 0; v < 3; ++v) n.row(mesh.faces(f, v)) += fn;
  }
  for (Eigen::Index k = 0; k < n.rows(); ++k) {
    const double len = n.row(k).norm();
    if (len > 0.0) n.row(k) /= len;
  }
  return n;
}

Eigen::VectorXd NormalDisplacement(const TriangleMesh& mesh, const Points3& moved) {
  if (moved.rows() != mesh.num_vertices())
    ThrowUsage("normal displacement needs the same number of vertices");
  const Points3 n = AreaWeightedNormals(mesh);
  return ((moved - mesh.vertices.positions).array() * n.array()).rowwise().sum();
}

Image ModeDisplacementImage(const ShapeModel& model, int mode, double sd) {
  if (mode < 1 || mode > model.num_modes()) {
    ThrowUsage("mode " + std::to_string(mode) + " does not exist; the model has " +
               std::to_string(model.num_modes()));
  }
  const TriangleMesh mean = model.ToMesh(model.mean);
  Eigen::VectorXd b = Eigen::VectorXd::Zero(mode);
  b[mode - 1] = sd;
  const Eigen::VectorXd d = NormalDisplacement(mean, FromShapeVector(model.Instance(b)));
  const double range = std::max(1e-6, d.cwiseAbs().maxCoeff());
  SurfaceMapFigure figure;
  char title[160];
  std::snprintf(title, sizeof(title), "mode %d, %+g sd (%.1f%%): along normals", mode, sd,
                100.0 * model.ExplainedFraction()[mode - 1]);
  figure.title = title;
  figure.min = -range;
  figure.max = range;
  return SurfaceMapImage(mean, d, Eigen::Vector3d::Zero(), figure);
}

void WriteModeDisplacementPng(const std::filesystem::path& path, const ShapeModel& model, int mode,
                              double sd) {
  render::WritePng(ModeDisplacementImage(model, mode, sd), path);
}

Image QualityCurvesImage(const ModelQualityCurves& q) {
  const std::vector<double> m = ToStd(q.modes.cast<double>());
  auto panel = [&](const Eigen::VectorXd& y, const Eigen::VectorXd& se, const std::string& title,
                   const std::string& unit, render::Rgb colour) {
    render::Series main{title, m, ToStd(y), colour, true, false};
    render::Series upper{"+-1 standard error", m, ToStd(y + se), colour, false, true};
    render::Series lower{"", m, ToStd(y - se), colour, false, true};
    render::PlotOptions o;
    o.title = title;
    o.x_label = "number of modes M";
    o.y_label = unit;
    o.width = 560;
    o.height = 420;
    return render::PlotLines({main, upper, lower}, o);
  };
  return render::HStack(
      {panel(q.compactness, q.compactness_sd, "compactness C(M)", "mm^2", {31, 119, 180}),
       panel(q.generalization_mm, q.generalization_sd, "generalization G(M)", "mm", {44, 160, 44}),
       panel(q.specificity_mm, q.specificity_sd, "specificity S(M)", "mm", {214, 39, 40})},
      10);
}

void WriteQualityCurvesPng(const std::filesystem::path& path, const ModelQualityCurves& curves) {
  render::WritePng(QualityCurvesImage(curves), path);
}

}  // namespace pectus
