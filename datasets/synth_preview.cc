#include "datasets/synth_preview.h"

#include <Eigen/Geometry>
#include <numbers>

#include "datasets/surface_query.h"
#include "shape/render/colormap.h"

namespace pectus::datasets {
namespace {

constexpr double kPreviewSpacingMm = 3.0;  // edge length of the rendered skin mesh

}  // namespace

render::View SubjectView(const SyntheticSubject& subject, double yaw_deg, double pitch_deg, int width,
                         int height) {
  render::View view = render::View::Oblique(yaw_deg, pitch_deg, width, height);
  const Eigen::Matrix3d R = subject.parameters.T_scan_subject.linear();
  view.direction = R * view.direction;
  view.up = R * view.up;
  return view;
}

render::Image RenderSkin(const SyntheticSubject& subject, const render::View& view, bool depth_colours) {
  const ChestSurface skin = subject.Skin();
  const TriangleMesh mesh = Tessellate(skin, kPreviewSpacingMm);
  if (!depth_colours || subject.parameters.pectus.depth_mm <= 0.0) return render::RenderMesh(mesh, view);
  ChestParameters flat = subject.parameters;
  flat.pectus = PectusParameters{};
  const ChestSurface normal(flat);
  const Eigen::VectorXd& u = mesh.vertices.scalars.at("u");
  const Eigen::VectorXd& v = mesh.vertices.scalars.at("v");
  Eigen::VectorXd depth(mesh.num_vertices());
  for (Eigen::Index k = 0; k < depth.size(); ++k) {
    depth(k) = (normal.Position(u(k), v(k)) - mesh.vertices.positions.row(k).transpose()).norm();
  }
  const Colors3 colours =
      render::MapColors(depth, 0.0, subject.parameters.pectus.depth_mm, render::Colormap::kViridis);
  return render::RenderMesh(mesh, view, &colours);
}

render::Image RenderSweeps(const Scan& scan, const render::View& view, bool true_poses) {
  PointCloud all;
  Eigen::Index n = 0;
  for (const Sweep& s : scan.sweeps) n += s.cloud.size();
  all.positions.resize(n, 3);
  Colors3 colours(n, 3);
  Eigen::Index row = 0;
  for (std::size_t k = 0; k < scan.sweeps.size(); ++k) {
    const Sweep& s = scan.sweeps[k];
    const render::Rgb c = render::CategoryColor(static_cast<int>(k));
    for (Eigen::Index i = 0; i < s.cloud.size(); ++i, ++row) {
      const Eigen::Vector3d p = s.cloud.positions.row(i).transpose();
      all.positions.row(row) = (true_poses ? Eigen::Vector3d(s.truth.T_scan_sweep * p) : p).transpose();
      colours.row(row) << c.r, c.g, c.b;
    }
  }
  return render::RenderPoints(all, view, &colours);
}

void WriteSubjectPreview(const ScannedSubject& subject, const std::filesystem::path& path,
                         const StagePath& stage) {
  const render::View view = SubjectView(subject.subject, 25.0, -15.0, 520, 520);
  std::vector<render::Image> panels;
  const bool pectus = subject.subject.parameters.pectus.depth_mm > 0.0;
  panels.push_back(render::WithTitle(RenderSkin(subject.subject, view, pectus),
                                     pectus ? "true skin, depression depth" : "true skin"));
  panels.push_back(render::WithTitle(RenderSweeps(subject.scan, view, false),
                                     std::to_string(subject.scan.sweeps.size()) + " sweeps, as tracked"));
  render::WritePng(render::WithTitle(render::HStack(panels, 8),
                                     subject.subject.name + " (" + subject.subject.origin + ")"),
                   stage ? stage(path) : path);
}

}  // namespace pectus::datasets
