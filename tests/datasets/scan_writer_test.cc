// Tests of datasets/scan_writer: a subject folder reads back as written, a staged write leaves nothing until
// it is committed, and the committed fixtures' sweeps, mapped by their true poses, lie on their true
// surfaces.
#include "datasets/scan_writer.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "datasets/surface_query.h"
#include "shape/core/atomic_file.h"
#include "shape/core/error.h"
#include "shape/io/mesh_io.h"

namespace pectus::datasets {
namespace {
namespace fs = std::filesystem;

const fs::path kFixtures = fs::path(PECTUS_SOURCE_DIR) / "datasets" / "fixtures";

ScannedSubject SmallSubject() {
  SubjectOptions o;
  o.pose_deg = 15.0;
  o.pose_mm = 50.0;
  PectusParameters pe;
  pe.depth_mm = 25.0;
  ScanOptions scan;
  scan.sweeps = 3;
  scan.spacing_mm = 4.0;
  return ScanSubject(MakeSubjectWithPectus(o, 12, 0, pe), scan, 1.0, 5);
}

fs::path TempFolder(const std::string& name) {
  const fs::path p =
      fs::temp_directory_path() / ("pectus_datasets_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(p);
  return p;
}

// Float PLY positions keep ~1e-5 mm at chest scale.
constexpr double kFloatMm = 1e-3;

TEST(ScanWriter, SubjectFolderReadsBackAsWritten) {
  const ScannedSubject s = SmallSubject();
  const fs::path folder = TempFolder("roundtrip");
  SubjectWriteOptions o;
  o.truth_spacing_mm = 6.0;
  const std::uintmax_t bytes = WriteSubjectFolder(s, folder, o);
  EXPECT_GT(bytes, 10000u);
  const SubjectFolder f = ReadSubjectFolder(folder);
  ASSERT_EQ(f.sweeps.size(), 3u);
  ASSERT_EQ(f.sweep_truth.size(), 3u);
  for (std::size_t k = 0; k < 3; ++k) {
    const Sweep& w = s.scan.sweeps[k];
    ASSERT_EQ(f.sweeps[k].size(), w.cloud.size());
    EXPECT_LT((f.sweeps[k].positions - w.cloud.positions).cwiseAbs().maxCoeff(), kFloatMm);
    EXPECT_LT((f.sweep_truth[k].positions - w.truth.true_points).cwiseAbs().maxCoeff(), kFloatMm);
    EXPECT_LT((f.T_scan_sweep[k].matrix() - w.truth.T_scan_sweep.matrix()).cwiseAbs().maxCoeff(), 1e-12);
    EXPECT_EQ(f.sweeps[k].scalars.count("line"), 1u);
  }
  for (std::size_t i = 0; i < s.true_landmarks.size(); ++i) {
    EXPECT_EQ(f.true_landmarks.items[i].label, s.true_landmarks.items[i].label);
    EXPECT_LT((f.true_landmarks.items[i].position - s.true_landmarks.items[i].position).norm(), 1e-9);
    EXPECT_LT((f.landmarks.items[i].position - s.placed_landmarks.items[i].position).norm(), 1e-9);
  }
  EXPECT_EQ(LinearPart(f.subject.parameters), LinearPart(s.subject.parameters));
  // The dense true mesh lies on the surface rebuilt from the written description.
  const ChestSurface skin = f.subject.Skin();
  const TriangleMesh mesh = ReadMesh(folder / kSurfaceFile);
  for (Eigen::Index k = 0; k < mesh.num_vertices(); k += 53) {
    EXPECT_LT(ClosestPoint(skin, mesh.vertices.positions.row(k).transpose()).distance, kFloatMm);
  }
  EXPECT_TRUE(fs::exists(folder / kChestWallFile));
  EXPECT_TRUE(fs::exists(folder / kPosesConfFile));
  fs::remove_all(folder);
}

TEST(ScanWriter, StagedWriteAppearsOnlyOnCommit) {
  const ScannedSubject s = SmallSubject();
  const fs::path folder = TempFolder("staged");
  SubjectWriteOptions o;
  o.truth_spacing_mm = 10.0;
  o.sweep_truth = false;
  o.chest_wall = false;
  {
    OutputTransaction failed;
    WriteSubjectFolder(s, folder, o, [&](const fs::path& p) { return failed.Stage(p); });
    EXPECT_FALSE(fs::exists(folder / SweepFileName(0)));
  }  // destroyed without commit: nothing stays behind
  EXPECT_FALSE(fs::exists(folder / SweepFileName(0)));
  OutputTransaction ok;
  WriteSubjectFolder(s, folder, o, [&](const fs::path& p) { return ok.Stage(p); });
  ok.CommitAll();
  EXPECT_TRUE(fs::exists(folder / SweepFileName(2)));
  EXPECT_FALSE(fs::exists(folder / SweepTruthFileName(0)));
  EXPECT_EQ(ReadSubjectFolder(folder).sweeps.size(), 3u);
  fs::remove_all(folder);
}

TEST(ScanWriter, MissingTruthIsABadInputNamingTheFile) {
  const fs::path folder = TempFolder("missing");
  fs::create_directories(folder);
  try {
    ReadSubjectFolder(folder);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::kBadInput);
    EXPECT_NE(std::string(e.what()).find("subject.json"), std::string::npos);
  }
  fs::remove_all(folder);
}

// The committed fixtures: each sweep mapped by its true pose lies on the true skin within its noise, outliers
// excepted, and the landmarks on the skin.
TEST(ScanWriter, FixturesSweepsMappedByTruePosesLieOnTheTrueSurface) {
  int subjects = 0;
  for (const fs::directory_entry& e : fs::recursive_directory_iterator(kFixtures)) {
    if (e.path().filename() != "subject.json") continue;
    const SubjectFolder f = ReadSubjectFolder(e.path().parent_path().parent_path());
    ++subjects;
    std::ifstream in(f.folder / kPosesFile);
    const nlohmann::json poses = nlohmann::json::parse(in);
    const double noise = poses["scan_options"]["noise_mm"].get<double>();
    const ChestSurface skin = f.subject.Skin();
    for (std::size_t k = 0; k < f.sweeps.size(); ++k) {
      const Eigen::VectorXd& outlier = f.sweep_truth[k].scalars.at("outlier");
      const double breathing = poses["sweeps"][k]["breathing_mm"].get<double>();
      const ChestSurface state = skin.WithBreathing(breathing);
      double sum2 = 0.0;
      int inliers = 0;
      for (Eigen::Index i = 0; i < f.sweeps[k].size(); ++i) {
        if (outlier(i) != 0.0) continue;
        ClosestPointOptions o;
        o.initial_uv =
            Eigen::Vector2d(f.sweep_truth[k].scalars.at("u")(i), f.sweep_truth[k].scalars.at("v")(i));
        const double d =
            ClosestPoint(state, f.T_scan_sweep[k] * Eigen::Vector3d(f.sweeps[k].positions.row(i).transpose()),
                         o)
                .signed_distance;
        EXPECT_LT(std::abs(d), 5.5 * noise + kFloatMm);
        sum2 += d * d;
        ++inliers;
      }
      EXPECT_LT(std::sqrt(sum2 / inliers), 1.05 * noise + kFloatMm) << f.folder << " sweep " << k;
    }
    for (const Landmark& l : f.true_landmarks.items) EXPECT_LT(ClosestPoint(skin, l.position).distance, 1e-6);
  }
  EXPECT_GE(subjects, 3);
}

}  // namespace
}  // namespace pectus::datasets
