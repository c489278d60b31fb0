// `pectus pipeline` as a user runs it, on a small cohort that `pectus synth cohort` makes: the run
// succeeds, and every row of the scores.csv it writes is the model's projection of that subject's grid
// (both read back from the files written: model.h5 and subjects/NAME/grid.ply); a work file that cannot be
// written is the error the run reports.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "shape/io/mesh_io.h"
#include "shape/model/shape_grid.h"
#include "shape/model/shape_model.h"
#include "shape/model/statismo_io.h"
#include "tests/support/cli_run.h"
#include "tests/support/scratch_dir.h"

namespace pectus {
namespace {
namespace fs = std::filesystem;

using testing_support::CliRun;
using testing_support::Pectus;

class PipelineCommand : public testing_support::ScratchDirTest {
 protected:
  PipelineCommand() : ScratchDirTest("pectus_pipeline_cli_") {}
};

std::vector<std::string> Split(const std::string& line) {
  std::vector<std::string> cells;
  std::stringstream in(line);
  for (std::string cell; std::getline(in, cell, ',');) cells.push_back(cell);
  return cells;
}

TEST_F(PipelineCommand, ScoresCsvHoldsEachSubjectsProjectionOnTheModel) {
  // Four subjects, three sweeps at 3 mm: coarse enough to run in seconds, fine enough to reconstruct.
  CliRun run = Pectus("synth cohort --subjects 4 --seed 3 --sweeps 3 --spacing 3 --no-sweep-truth -o " +
                      P("cohort") + " --quiet");
  ASSERT_EQ(run.code, 0) << run.output;
  run = Pectus("pipeline " + P("cohort") + " --out " + P("out") +
               " --grid 21x41 --surface-spacing 3 --merge-spacing 0 --no-quality --no-surfaces --quiet");
  ASSERT_EQ(run.code, 0) << run.output;

  const ShapeModel model = ReadStatismoModel(P("out/model.h5"));
  ASSERT_EQ(model.names.size(), 4u);
  ASSERT_GE(model.num_modes(), 2);  // with one mode the old column mix-up could not show
  std::ifstream csv(P("out/scores.csv"));
  std::string line;
  ASSERT_TRUE(std::getline(csv, line));
  std::vector<std::string> header = Split(line);
  ASSERT_EQ(header.size(), static_cast<std::size_t>(model.num_modes()) + 1);
  EXPECT_EQ(header[0], "subject");
  EXPECT_EQ(header[1], "mode1_mm");
  std::size_t rows = 0;
  for (; std::getline(csv, line); ++rows) {
    const std::vector<std::string> cells = Split(line);
    ASSERT_EQ(cells.size(), header.size()) << line;
    ASSERT_LT(rows, model.names.size());
    EXPECT_EQ(cells[0], model.names[rows]);
    const TriangleMesh grid = ReadMesh(P("out/subjects/" + cells[0] + "/grid.ply"));
    const ShapeProjection p = ProjectShape(model, ToShapeVector(grid.vertices.positions));
    for (int k = 0; k < model.num_modes(); ++k) {
      // The files hold single precision (the grid's PLY coordinates, the model's mean and basis in HDF5):
      // about 2e-5 mm on coordinates of 300 mm, and a score is a unit-basis dot product of them, so the
      // projection of the read-back grid agrees with the pipeline's score to about 1e-4 mm. 1e-3 mm leaves
      // a margin ten times that, and the scores themselves are tens of millimetres: a row holding another
      // subject's score (the defect this test guards against) is off by millimetres.
      EXPECT_NEAR(std::stod(cells[static_cast<std::size_t>(k) + 1]), p.scores[k], 1e-3)
          << cells[0] << ", mode " << k + 1;
    }
  }
  EXPECT_EQ(rows, model.names.size());
}

TEST_F(PipelineCommand, AWorkFileThatCannotBeWrittenIsTheErrorReportedAndNothingIsWritten) {
  // A subject's summary cannot be written (its folder in the work folder is a file, as a full disk or a
  // lost mount would make it fail): that failure is what the run reports, not a missing summary read
  // after it, and no output is left behind.
  CliRun run = Pectus("synth cohort --subjects 4 --seed 3 --sweeps 3 --spacing 3 --no-sweep-truth -o " +
                      P("cohort") + " --quiet");
  ASSERT_EQ(run.code, 0) << run.output;
  fs::create_directories(P("out/.pectus-work"));
  std::ofstream(P("out/.pectus-work/summary")) << "not a folder";
  run = Pectus(
      "pipeline " + P("cohort") + " --out " + P("out") +
      " --grid 21x41 --surface-spacing 3 --merge-spacing 0 --no-quality --no-surfaces --resume --quiet");
  EXPECT_EQ(run.code, 1) << run.output;
  // The write's own message ("…/summary: cannot create folder: Not a directory"), not the read of a
  // summary that was never written ("…/summary/NAME.rec: cannot open", which it was until 2026-11-28).
  EXPECT_NE(run.output.find("summary: cannot create folder"), std::string::npos) << run.output;
  EXPECT_EQ(run.output.find("cannot open"), std::string::npos) << run.output;
  EXPECT_FALSE(fs::exists(P("out/model.h5")));
  EXPECT_FALSE(fs::exists(P("out/report.html")));
  EXPECT_TRUE(fs::exists(P("out/.pectus-work/registered"))) << "the subjects' results are kept for --resume";
}

}  // namespace
}  // namespace pectus
