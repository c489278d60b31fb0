// `pectus reconstruct` and `pectus merge` as a user meets them: a sphere cloud gives a watertight surface on
// the sphere with the report the issue asks for; bad input (too few points, NaN, all points on a line, no
// normals obtainable, a missing sweep) exits 3 with a message naming the file, and writes nothing.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "shape/core/number_format.h"
#include "shape/io/mesh_io.h"
#include "tests/support/command_test.h"

namespace pectus {
namespace {

class ReconstructCommand : public testing_support::CommandTest {
 protected:
  // n points of a sphere of radius r (Fibonacci lattice), as ASCII XYZ.
  void WriteSphere(const std::string& name, int n, double r) const {
    std::ofstream out(P(name));
    const double golden = M_PI * (3.0 - std::sqrt(5.0));
    for (int i = 0; i < n; ++i) {
      const double z = 1.0 - 2.0 * (i + 0.5) / n, rho = std::sqrt(1.0 - z * z);
      out << r * rho * std::cos(golden * i) << " " << r * rho * std::sin(golden * i) << " " << r * z << "\n";
    }
  }
};

TEST_F(ReconstructCommand, SphereGivesAWatertightSurfaceOnTheSphereAndAReport) {
  WriteSphere("sphere.xyz", 6000, 30.0);
  const CliRun run = Pectus("reconstruct " + P("sphere.xyz") + " -o " + P("surface.ply") +
                            " --spacing 1.5 --fill-holes 30 --quiet --report " + P("r.json"));
  ASSERT_EQ(run.code, 0) << run.output;
  const TriangleMesh mesh = ReadMesh(P("surface.ply"));
  ASSERT_GT(mesh.num_faces(), 1000);
  const Eigen::ArrayXd radius = mesh.vertices.positions.rowwise().norm().array();
  EXPECT_LT((radius - 30.0).abs().maxCoeff(), 0.1);
  std::ifstream in(P("r.json"));
  const nlohmann::json report = nlohmann::json::parse(in);
  EXPECT_EQ(report["faces"].get<long long>(), mesh.num_faces());
  EXPECT_EQ(report["vertices"].get<long long>(), mesh.num_vertices());
  EXPECT_GE(report["fitting"]["carr_max_residual_mm"].get<double>(), 0.0);
  EXPECT_LT(report["fitting"]["carr_max_residual_mm"].get<double>(), 0.5);
  // The summary gives the on-surface residuals (0.011 mm RMS and 0.021 mm p95 measured: a few times that
  // here), each with three significant digits, not Carr's maximum over every constraint (0.11 mm).
  const double rms = report["fitting"]["on_surface_rms_mm"].get<double>();
  const double p95 = report["fitting"]["on_surface_p95_mm"].get<double>();
  EXPECT_LT(rms, 0.05);
  EXPECT_LT(p95, 0.08);
  EXPECT_LE(rms, p95);
  EXPECT_LE(p95, report["fitting"]["carr_max_residual_mm"].get<double>());
  const std::string summary = report["message"].get<std::string>();
  EXPECT_NE(summary.find("on-surface residual RMS " + FormatMm(rms) + ", p95 " + FormatMm(p95)),
            std::string::npos)
      << summary;
  EXPECT_EQ(summary.find("accuracy"), std::string::npos) << summary;
  EXPECT_TRUE(report["watertight"].get<bool>());
  EXPECT_TRUE(report["check"]["manifold"].get<bool>());
  EXPECT_FALSE(report["check"]["self_intersecting"].get<bool>());
  // STL and OBJ are written too.
  for (const char* ext : {"stl", "obj"}) {
    const std::string out = P(std::string("surface.") + ext);
    ASSERT_EQ(Pectus("reconstruct " + P("sphere.xyz") + " -o " + out + " --spacing 1.5 --quiet").code, 0)
        << ext;
    EXPECT_EQ(ReadMesh(out).num_faces(), mesh.num_faces()) << ext;
  }
}

TEST_F(ReconstructCommand, BadInputExitsThreeNamesTheFileAndWritesNothing) {
  WriteSphere("few.xyz", 10, 30.0);
  ExpectBadInput("reconstruct " + P("few.xyz") + " -o " + P("out.ply"), "few.xyz", "at least 16");

  {
    std::ofstream out(P("line.xyz"));
    for (int i = 0; i < 300; ++i) out << 0.5 * i << " " << 2.0 * i << " " << -1.0 * i << "\n";
  }
  ExpectBadInput("reconstruct " + P("line.xyz") + " -o " + P("out.ply"), "line.xyz", "one line");

  {
    std::ofstream out(P("nan.xyz"));
    for (int i = 0; i < 300; ++i) out << 0.5 * i << " " << (i == 77 ? "nan" : "1.0") << " " << i % 17 << "\n";
  }
  ExpectBadInput("reconstruct " + P("nan.xyz") + " -o " + P("out.ply"), "nan.xyz", "");

  {  // scan lines 20 mm apart, points 0.2 mm apart along them: every neighbourhood is a line
    std::ofstream out(P("lines.xyz"));
    for (int l = 0; l < 10; ++l)
      for (int i = 0; i < 500; ++i) out << 0.2 * i << " " << 20.0 * l << " " << 0.01 * l * l << "\n";
  }
  ExpectBadInput("reconstruct " + P("lines.xyz") + " -o " + P("out.ply"), "lines.xyz",
                 "no normals obtainable");
}

TEST_F(ReconstructCommand, MergeOfAMissingSweepExitsThreeAndWritesNothing) {
  WriteSphere("a.xyz", 2000, 30.0);
  ExpectBadInput("merge " + P("a.xyz") + " " + P("missing.xyz") + " -o " + P("merged.ply") + " --poses-out " +
                     P("aligned.conf"),
                 "missing.xyz", "");
}

}  // namespace
}  // namespace pectus
