// A subject's record: every field read back bit for bit (arrays of every kind, empty ones too), and a file
// that is not a record (truncated, another version's pure CBOR, garbage) a clear error naming the file.
#include "shape/pipeline/internal/subject_record.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <random>

#include "shape/core/error.h"

namespace pectus::internal {
namespace {

namespace fs = std::filesystem;

SubjectOutcome SomeSubject() {
  std::mt19937_64 rng(7);
  std::normal_distribution<double> g(0.0, 50.0);
  auto random = [&](auto* m, Eigen::Index rows, Eigen::Index cols) {
    m->resize(rows, cols);
    for (Eigen::Index k = 0; k < m->size(); ++k)
      m->data()[k] = static_cast<typename std::decay_t<decltype(*m)>::Scalar>(g(rng));
  };
  SubjectOutcome s;
  s.name = "subject_017";
  s.ok = true;
  s.sweeps = 3;
  s.sweep_files = {"a/sweep_0.ply", "a/sweep_1.ply", "a/sweep_2.ply"};
  s.T_subject_sweep.assign(3, Rigid3::Identity());
  s.T_subject_sweep[1].translation() << 1.5, -2.25, 1e-300;
  s.points_in = 123456789012, s.points_merged = 98765;
  s.merge_rms_mm = 0.1 + 0.2;
  s.T_reference_subject.scale = 1.0000000000000002;
  s.T_reference_subject.translation << g(rng), g(rng), g(rng);
  random(&s.surface.vertices.positions, 1000, 3);
  random(&s.surface.vertices.normals, 1000, 3);
  random(&s.surface.faces, 1900, 3);
  s.surface.vertices.scalars["data_distance"] = Eigen::VectorXd::LinSpaced(1000, -1.0, 1.0);
  s.landmarks.items.push_back({"sternal notch", {g(rng), g(rng), g(rng)}, "SN"});
  random(&s.grid.mesh.vertices.positions, 51 * 101, 3);
  s.grid.mesh.vertices.scalars["scan_gap_mm"] = Eigen::VectorXd::Constant(51 * 101, 0.25);
  s.grid.shape_vector = Eigen::VectorXd::LinSpaced(3 * 51 * 101, 0.0, 1.0);
  s.grid.fit_rms_mm = std::numeric_limits<double>::quiet_NaN();
  s.measures.depression_depth_mm = 17.125;
  s.scores = Eigen::VectorXd::LinSpaced(9, -4.0, 4.0);
  random(&s.to_mean.distances, 51 * 101, 1);
  s.to_mean.stats.p99 = 3.5;
  s.timings_s.Add("merge", 1.25);
  return s;
}

template <class M>
bool SameBits(const M& a, const M& b) {
  return a.rows() == b.rows() && a.cols() == b.cols() &&
         std::memcmp(a.data(), b.data(), sizeof(typename M::Scalar) * static_cast<std::size_t>(a.size())) ==
             0;
}

TEST(SubjectRecord, ReadsBackEveryFieldBitForBit) {
  const fs::path path = fs::temp_directory_path() / "pectus_subject_record_test.rec";
  const SubjectOutcome s = SomeSubject();
  WriteSubjectRecord(path, s);
  const SubjectOutcome r = ReadSubjectRecord(path);
  fs::remove(path);
  EXPECT_EQ(r.name, s.name);
  EXPECT_EQ(r.sweep_files, s.sweep_files);
  ASSERT_EQ(r.T_subject_sweep.size(), 3u);
  EXPECT_TRUE(SameBits(r.T_subject_sweep[1].matrix(), s.T_subject_sweep[1].matrix()));
  EXPECT_EQ(r.points_in, s.points_in);
  EXPECT_EQ(r.merge_rms_mm, s.merge_rms_mm);
  EXPECT_EQ(r.T_reference_subject.scale, s.T_reference_subject.scale);
  EXPECT_TRUE(SameBits(r.T_reference_subject.translation, s.T_reference_subject.translation));
  EXPECT_TRUE(SameBits(r.surface.vertices.positions, s.surface.vertices.positions));
  EXPECT_TRUE(SameBits(r.surface.vertices.normals, s.surface.vertices.normals));
  EXPECT_TRUE(SameBits(r.surface.faces, s.surface.faces));
  EXPECT_EQ(r.surface.vertices.colors.rows(), 0);
  EXPECT_TRUE(SameBits(r.surface.vertices.scalars.at("data_distance"),
                       s.surface.vertices.scalars.at("data_distance")));
  ASSERT_EQ(r.landmarks.size(), 1u);
  EXPECT_TRUE(SameBits(r.landmarks.items[0].position, s.landmarks.items[0].position));
  EXPECT_EQ(r.landmarks.items[0].description, "SN");
  EXPECT_TRUE(SameBits(r.grid.mesh.vertices.positions, s.grid.mesh.vertices.positions));
  EXPECT_TRUE(SameBits(r.grid.shape_vector, s.grid.shape_vector));
  EXPECT_TRUE(std::isnan(r.grid.fit_rms_mm));
  EXPECT_EQ(r.measures.depression_depth_mm, 17.125);
  EXPECT_TRUE(SameBits(r.scores, s.scores));
  EXPECT_TRUE(SameBits(r.to_mean.distances, s.to_mean.distances));
  EXPECT_EQ(r.to_mean.stats.p99, 3.5);
  EXPECT_EQ(r.timings_s.Seconds("merge"), 1.25);
}

TEST(SubjectRecord, AFileThatIsNotARecordIsAClearError) {
  const fs::path path = fs::temp_directory_path() / "pectus_subject_record_bad.rec";
  WriteSubjectRecord(path, SomeSubject());
  const auto size = fs::file_size(path);
  std::string bytes(size, '\0');
  std::ifstream(path, std::ios::binary).read(bytes.data(), static_cast<std::streamsize>(size));
  const std::vector<std::string> bad = {
      bytes.substr(0, 5),               // shorter than the CBOR's length
      bytes.substr(0, 40),              // the CBOR cut
      bytes.substr(0, size - 1000),     // the arrays cut
      std::string("\xa1\x61x\x01", 4),  // a CBOR document of another version (no length first)
      std::string(200, '\xff')};
  for (const std::string& b : bad) {
    std::ofstream(path, std::ios::binary | std::ios::trunc)
        .write(b.data(), static_cast<std::streamsize>(b.size()));
    try {
      ReadSubjectRecord(path);
      ADD_FAILURE() << "read a file of " << b.size() << " bytes";
    } catch (const Error& e) {
      EXPECT_EQ(e.kind(), ErrorKind::kBadInput);
      EXPECT_THAT(e.what(), ::testing::HasSubstr("pectus_subject_record_bad.rec"));
      EXPECT_THAT(e.what(), ::testing::HasSubstr("is not a pectus subject record"));
    }
  }
  fs::remove(path);
}

}  // namespace
}  // namespace pectus::internal
