#include "shape/core/atomic_file.h"

#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

#include "shape/core/error.h"

namespace pectus {
namespace {
namespace fs = std::filesystem;

class AtomicFileTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("pectus_atomic_" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  static std::string Slurp(const fs::path& p) {
    std::ifstream in(p, std::ios::binary);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
  }
  std::size_t CountFiles() const {
    return static_cast<std::size_t>(std::distance(fs::directory_iterator(dir_), {}));
  }
  fs::path dir_;
};

TEST_F(AtomicFileTest, CommitReplacesTargetWholly) {
  const fs::path target = dir_ / "out.txt";
  WriteFileAtomically(target, "old");
  {
    AtomicOutput out(target);
    out.stream() << "new contents";
    EXPECT_EQ(Slurp(target), "old");  // nothing visible before Commit
    out.Commit();
  }
  EXPECT_EQ(Slurp(target), "new contents");
  EXPECT_EQ(CountFiles(), 1u);
}

TEST_F(AtomicFileTest, AbandonedOutputLeavesTargetAndNoTemporary) {
  const fs::path target = dir_ / "keep.ply";
  WriteFileAtomically(target, "original");
  try {
    AtomicOutput out(target);
    out.stream() << "half";
    throw std::runtime_error("failure mid-write");
  } catch (const std::runtime_error&) {
  }
  EXPECT_EQ(Slurp(target), "original");
  EXPECT_EQ(CountFiles(), 1u);
}

TEST_F(AtomicFileTest, TransactionCommitsAllOrNothing) {
  {
    OutputTransaction tx;
    WriteFileAtomically(tx.Stage(dir_ / "a.ply"), "a");
    WriteFileAtomically(tx.Stage(dir_ / "sub" / "b.json"), "b");
    EXPECT_FALSE(fs::exists(dir_ / "a.ply"));
  }  // destroyed without commit
  EXPECT_FALSE(fs::exists(dir_ / "a.ply"));
  EXPECT_FALSE(fs::exists(dir_ / "sub" / "b.json"));
  EXPECT_TRUE(fs::is_empty(dir_ / "sub"));
  {
    OutputTransaction tx;
    const fs::path staged = tx.Stage(dir_ / "a.ply");
    EXPECT_EQ(staged.extension(), ".ply");  // format detection by extension still works
    WriteFileAtomically(staged, "a");
    WriteFileAtomically(tx.Stage(dir_ / "sub" / "b.json"), "b");
    tx.CommitAll();
  }
  EXPECT_EQ(Slurp(dir_ / "a.ply"), "a");
  EXPECT_EQ(Slurp(dir_ / "sub" / "b.json"), "b");
}

TEST_F(AtomicFileTest, MovesAtCommitOnlyAndLeavesTheSourcesOtherwise) {
  // A work folder's results: a subject's folder and a picture.
  const fs::path work = dir_ / "work", out = dir_ / "out";
  WriteFileAtomically(work / "s1" / "grid.ply", "grid");
  WriteFileAtomically(work / "s1" / "deep" / "x.json", "x");
  WriteFileAtomically(work / "s1.png", "png");
  // An earlier run's outputs: the folder is replaced whole, the file overwritten.
  WriteFileAtomically(out / "subjects" / "s1" / "stale.ply", "old");
  WriteFileAtomically(out / "figures" / "s1.png", "old png");
  {
    OutputTransaction tx;
    tx.MoveAtCommit(work / "s1", out / "subjects" / "s1");
    tx.MoveAtCommit(work / "s1.png", out / "figures" / "s1.png");
    WriteFileAtomically(tx.Stage(out / "report.html"), "report");
  }  // destroyed without commit: the sources stay, the outputs are as they were
  EXPECT_EQ(Slurp(work / "s1" / "grid.ply"), "grid");
  EXPECT_EQ(Slurp(work / "s1.png"), "png");
  EXPECT_EQ(Slurp(out / "subjects" / "s1" / "stale.ply"), "old");
  EXPECT_FALSE(fs::exists(out / "report.html"));
  {
    OutputTransaction tx;
    tx.MoveAtCommit(work / "s1", out / "subjects" / "s1");
    tx.MoveAtCommit(work / "s1.png", out / "figures" / "s1.png");
    const fs::path late = tx.Stage(out / "run.json");  // written after the first commit
    WriteFileAtomically(tx.Stage(out / "report.html"), "report");
    EXPECT_FALSE(fs::exists(out / "subjects" / "s1" / "grid.ply"));
    tx.CommitAll();
    EXPECT_EQ(Slurp(out / "subjects" / "s1" / "grid.ply"), "grid");
    EXPECT_EQ(Slurp(out / "subjects" / "s1" / "deep" / "x.json"), "x");
    EXPECT_FALSE(fs::exists(out / "subjects" / "s1" / "stale.ply"));
    EXPECT_EQ(Slurp(out / "figures" / "s1.png"), "png");
    EXPECT_EQ(Slurp(out / "report.html"), "report");
    EXPECT_FALSE(fs::exists(work / "s1"));
    EXPECT_FALSE(fs::exists(out / "run.json"));
    WriteFileAtomically(late, "run");
    tx.CommitAll();  // the stage written since
    EXPECT_EQ(Slurp(out / "run.json"), "run");
  }
  EXPECT_EQ(Slurp(out / "run.json"), "run");
  std::size_t left = 0;  // no temporary left beside the outputs
  for (const auto& e : fs::recursive_directory_iterator(out))
    left += e.path().filename().string().find("pectus-tmp") != std::string::npos;
  EXPECT_EQ(left, 0u);
}

TEST_F(AtomicFileTest, RefusesAnOutputFolderThatHoldsAnInput) {
  const fs::path in = dir_ / "cohort" / "s1" / "sweep_00.ply";
  WriteFileAtomically(in, "x");
  const InputGuard guard({in});
  // By its path, however the folder is spelled.
  EXPECT_THROW(guard.RefuseFolder(dir_ / "cohort" / "s1"), Error);
  EXPECT_THROW(guard.RefuseFolder(dir_ / "cohort" / ".." / "cohort"), Error);
  EXPECT_THROW(guard.RefuseFolder(dir_), Error);
  // A folder whose name only begins like the input's is not its folder.
  EXPECT_NO_THROW(guard.RefuseFolder(dir_ / "cohort" / "s"));
  EXPECT_NO_THROW(guard.RefuseFolder(dir_ / "out" / "s1"));
  // By identity: an existing folder holding a link to the input.
  fs::create_directories(dir_ / "out" / "s1");
  fs::create_hard_link(in, dir_ / "out" / "s1" / "linked.ply");
  try {
    guard.RefuseFolder(dir_ / "out" / "s1");
    FAIL() << "a folder holding a hard link to an input was not refused";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::kUsage);
    EXPECT_NE(std::string(e.what()).find("linked.ply"), std::string::npos) << e.what();
  }
}

TEST_F(AtomicFileTest, RefusesOutputEqualToInput) {
  const fs::path in = dir_ / "scan.ply";
  WriteFileAtomically(in, "x");
  EXPECT_THROW(RefuseOverwritingInputs(dir_ / "." / "scan.ply", {in}), Error);
  fs::create_symlink(in, dir_ / "link.ply");
  EXPECT_THROW(RefuseOverwritingInputs(dir_ / "link.ply", {in}), Error);
  EXPECT_NO_THROW(RefuseOverwritingInputs(dir_ / "other.ply", {in}));
}

TEST_F(AtomicFileTest, UnwritableFolderIsAClearFailure) {
  const fs::path blocker = dir_ / "file";
  WriteFileAtomically(blocker, "x");
  try {
    AtomicOutput out(blocker / "out.ply");  // parent is a file
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::kFailure);
  }
}

}  // namespace
}  // namespace pectus
