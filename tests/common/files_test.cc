// common/files.h: a folder replaced as a whole (FolderReplacement, ReplaceDirectory) never loses
// the folder it replaces when the writer fails, and never keeps a stale file of it when it does
// not.

#include "common/files.h"

#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace netlab {
namespace {

namespace fs = std::filesystem;

class FolderReplacementTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("netlab_files_" + std::to_string(getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  static void Write(const fs::path& path, const std::string& text) {
    fs::create_directories(path.parent_path());
    std::ofstream(path) << text;
  }
  // Every file under `folder`, relative path -> content.
  static std::map<std::string, std::string> Contents(const fs::path& folder) {
    std::map<std::string, std::string> files;
    for (const auto& entry : fs::recursive_directory_iterator(folder)) {
      if (!entry.is_regular_file()) continue;
      std::stringstream text;
      text << std::ifstream(entry.path()).rdbuf();
      files[fs::relative(entry.path(), folder).string()] = text.str();
    }
    return files;
  }
  // The folder's entries' names.
  std::vector<std::string> Entries() const {
    std::vector<std::string> names;
    for (const auto& entry : fs::directory_iterator(dir_))
      names.push_back(entry.path().filename().string());
    std::sort(names.begin(), names.end());
    return names;
  }

  fs::path dir_;
};

TEST_F(FolderReplacementTest, AFailingWriterLeavesTheOldFolderAndNoPartial) {
  const fs::path shot = dir_ / "shot";
  Write(shot / "a.txt", "old a");
  Write(shot / "cam0" / "b.txt", "old b");
  const auto before = Contents(shot);
  try {
    FolderReplacement folder(shot.string());
    Write(fs::path(folder.partial()) / "a.txt", "new a");
    throw std::runtime_error("the writer fails half way");
  } catch (const std::runtime_error&) {
  }
  EXPECT_EQ(Contents(shot), before);
  EXPECT_EQ(Entries(), std::vector<std::string>{"shot"});  // no shot.partial, no shot.old.*
}

TEST_F(FolderReplacementTest, CommitReplacesTheWholeFolder) {
  const fs::path shot = dir_ / "shot";
  Write(shot / "a.txt", "old a");
  Write(shot / "cam0" / "frame_9.pgm", "a stale frame");
  {
    FolderReplacement folder(shot.string() + "/");  // a trailing '/' names the same folder
    EXPECT_EQ(folder.partial(), shot.string() + ".partial");
    Write(fs::path(folder.partial()) / "a.txt", "new a");
    folder.Commit();
  }
  EXPECT_EQ(Contents(shot), (std::map<std::string, std::string>{{"a.txt", "new a"}}));
  EXPECT_EQ(Entries(), std::vector<std::string>{"shot"});
}

TEST_F(FolderReplacementTest, AStalePartialIsRemovedFirstAndANewFolderIsCreated) {
  Write(dir_ / "new.partial" / "left_by_a_killed_run.txt", "stale");
  {
    FolderReplacement folder((dir_ / "new").string());
    EXPECT_TRUE(fs::is_empty(folder.partial()));
    Write(fs::path(folder.partial()) / "x.txt", "x");
    folder.Commit();
  }
  EXPECT_EQ(Contents(dir_ / "new"), (std::map<std::string, std::string>{{"x.txt", "x"}}));
  EXPECT_EQ(Entries(), std::vector<std::string>{"new"});
}

TEST_F(FolderReplacementTest, AFileOrTheWorkingFolderIsNotReplaced) {
  Write(dir_ / "file", "a file, not a folder");
  try {
    FolderReplacement folder((dir_ / "file").string());
    ADD_FAILURE() << "a file was taken for a folder";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("exists and is not a folder"), std::string::npos)
        << e.what();
  }
  EXPECT_EQ(Contents(dir_).at("file"), "a file, not a folder");
  for (const std::string name : {".", "..", "/", "a/.."})
    EXPECT_THROW(FolderReplacement folder(name), std::runtime_error) << name;
}

TEST(IsInsideFolder, ResolvesDotsAndNeedsNoFiles) {
  EXPECT_TRUE(IsInsideFolder("/tmp/shot/sim.h5", "/tmp/shot"));
  EXPECT_TRUE(IsInsideFolder("/tmp/shot/../shot/sim.h5", "/tmp/shot/"));
  EXPECT_TRUE(IsInsideFolder("/tmp/shot", "/tmp/shot"));
  EXPECT_FALSE(IsInsideFolder("/tmp/shot2/sim.h5", "/tmp/shot"));
  EXPECT_FALSE(IsInsideFolder("/tmp/sim.h5", "/tmp/shot"));
}

}  // namespace
}  // namespace netlab
