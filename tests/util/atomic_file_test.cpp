// AtomicFile: the target is either the complete new content or what it was before; never half.
#include "util/atomic_file.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>

#include <unistd.h>

namespace rths::util {
namespace {

namespace fs = std::filesystem;

class AtomicFileTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("rths_atomic_file_" +
            std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()) + "_" +
            std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  static std::string slurp(const fs::path& path) {
    std::ifstream in(path);
    std::ostringstream text;
    text << in.rdbuf();
    return text.str();
  }

  fs::path dir_;
};

TEST_F(AtomicFileTest, CommitPutsTheContentInPlaceAndLeavesNoPartialFile) {
  const fs::path target = dir_ / "sub" / "out.txt";  // the folder is made on the way
  {
    AtomicFile file(target);
    EXPECT_EQ(file.partial_path(), fs::path(target.string() + ".partial"));
    file.stream() << "new " << 0.1 << "\n";
    EXPECT_FALSE(fs::exists(target)) << "visible before commit";
    file.commit();
  }
  EXPECT_EQ(slurp(target), "new 0.10000000000000001\n");  // 17 significant digits
  EXPECT_FALSE(fs::exists(target.string() + ".partial"));
}

TEST_F(AtomicFileTest, AWriteThatFailsBeforeCommitLeavesTheOldFileIntact) {
  const fs::path target = dir_ / "out.txt";
  std::ofstream(target) << "old\n";
  try {
    AtomicFile file(target);
    file.stream() << "half of the new content";
    throw std::runtime_error("the writer failed");
  } catch (const std::runtime_error&) {}
  EXPECT_EQ(slurp(target), "old\n");
  EXPECT_FALSE(fs::exists(target.string() + ".partial"));
}

TEST_F(AtomicFileTest, ACommitThatCannotRenameThrowsNamingTheFileAndLeavesTheTargetAlone) {
  const fs::path target = dir_ / "taken";
  fs::create_directories(target / "inside");  // a non-empty folder: nothing may be renamed over it
  AtomicFile file(target);
  file.stream() << "content\n";
  try {
    file.commit();
    FAIL() << "renamed over a folder";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(target.string()), std::string::npos) << e.what();
  }
  EXPECT_TRUE(fs::is_directory(target / "inside"));
}

TEST_F(AtomicFileTest, AFolderThatCannotBeMadeIsNamed) {
  const fs::path file_in_the_way = dir_ / "plain_file";
  std::ofstream(file_in_the_way) << "x";
  EXPECT_THROW(AtomicFile(file_in_the_way / "out.txt"), std::runtime_error);
}

}  // namespace
}  // namespace rths::util
