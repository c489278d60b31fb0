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
    dir_ = fs::temp_directory_path() / ("pectus_atomic_" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()) +
                                        "_" + ::testing::UnitTest::GetInstance()->current_test_info()->name());
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
  std::size_t CountFiles() const { return static_cast<std::size_t>(std::distance(fs::directory_iterator(dir_), {})); }
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
