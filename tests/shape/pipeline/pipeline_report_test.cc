// The pipeline's HTML report on a hand-made result: three subjects whose grids are planes offset from the
// mean by known amounts and one that failed. Every picture the page shows is produced and is a PNG; the
// numbers of each subject, the failure and the common colour scale are on the page.
#include "shape/pipeline/pipeline_report.h"

#include <gtest/gtest.h>

#include <regex>
#include <set>

#include "shape/model/shape_grid.h"

namespace pectus {
namespace {

// Subject k: the plane w = offset_k over a 10 x 20 grid of a 100 x 200 mm ROI.
SubjectOutcome PlaneSubject(const std::string& name, double offset, const TriangleMesh& mean) {
  SubjectOutcome s;
  s.name = name;
  s.ok = true;
  s.grid.grid = GridSize{10, 20};
  s.grid.roi.u_min = -50.0;
  s.grid.roi.u_max = 50.0;
  s.grid.roi.v_max = 200.0;
  s.grid.mesh = mean;
  s.grid.mesh.vertices.positions.col(2).array() += offset;
  s.grid.shape_vector = ToShapeVector(s.grid.mesh.vertices.positions);
  s.to_mean = ComputeDistanceMap(s.grid.mesh.vertices.positions, mean);
  return s;
}

TEST(PipelineReport, ShowsEveryFigureEveryNumberAndTheFailure) {
  const GridSize g{10, 20};
  TriangleMesh plane;
  plane.vertices.positions.resize(g.num_vertices(), 3);
  for (int i = 0; i < g.sternal; ++i) {
    for (int j = 0; j < g.lateral; ++j)
      plane.vertices.positions.row(g.Index(i, j)) << -50.0 + 100.0 * j / 9, -200.0 * i / 19, 0.0;
  }
  // The grid's faces point along -y x x = +z, the ROI normal here.
  plane.faces = GridFaces(g);
  PipelineResult r;
  for (double offset : {-1.5, 0.5, 1.0})
    r.subjects.push_back(PlaneSubject("s" + std::to_string(r.subjects.size()), offset, plane));
  SubjectOutcome failed;
  failed.name = "broken";
  failed.failed_stage = "merge";
  failed.error = "broken/sweep_01.ply: a sweep overlaps no other sweep";
  r.subjects.push_back(failed);
  Eigen::MatrixXd shapes(3, 3 * g.num_vertices());
  for (int k = 0; k < 3; ++k) shapes.row(k) = r.subjects[k].grid.shape_vector.transpose();
  r.model = BuildShapeModel(shapes);
  r.model->faces = plane.faces;
  r.succeeded = 3;
  r.reference = "s0";
  r.message = "3 of 4 subjects made it to the model";

  const std::vector<ReportFile> files = MakePipelineReport(r);
  ASSERT_FALSE(files.empty());
  EXPECT_EQ(files.back().path, "report.html");
  const std::string& html = files.back().bytes;
  std::set<std::string> made;
  for (const ReportFile& f : files) {
    if (f.path == "report.html") continue;
    made.insert(f.path);
    ASSERT_GT(f.bytes.size(), 8u);
    EXPECT_EQ(f.bytes.substr(1, 3), "PNG") << f.path;
  }
  // Every <img> on the page is one of the files, and every file is on the page.
  std::set<std::string> shown;
  const std::regex img("<img src=\"([^\"]+)\"");
  for (auto it = std::sregex_iterator(html.begin(), html.end(), img); it != std::sregex_iterator(); ++it) {
    shown.insert((*it)[1]);
  }
  EXPECT_EQ(shown, made);
  EXPECT_TRUE(made.count("figures/distance_s0.png"));
  EXPECT_TRUE(made.count("figures/mode_1.png"));
  // The failure with its stage and message; the common scale: the largest offset, 1.5 mm, rounded up.
  EXPECT_NE(html.find("failed at merge"), std::string::npos);
  EXPECT_NE(html.find("a sweep overlaps no other sweep"), std::string::npos);
  EXPECT_NE(html.find("&plusmn;2.0 mm"), std::string::npos);
  // Subject s0 is 1.5 mm behind the mean everywhere (mean offset 0): RMS and max 1.50 mm.
  EXPECT_NE(html.find("RMS 1.50 mm, max 1.50 mm"), std::string::npos);
  const nlohmann::json j = PipelineJson(r);
  EXPECT_EQ(j["subjects"][3]["failed_stage"], "merge");
  EXPECT_NEAR(j["subjects"][0]["distance_to_mean"]["rms_mm"].get<double>(), 1.5, 1e-9);
}

}  // namespace
}  // namespace pectus
