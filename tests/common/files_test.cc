// common/files.h: a folder replaced as a whole (FolderReplacement, ReplaceDirectory) never loses
// the folder it replaces when the writer fails, and never keeps a stale file of it when it does
// not; the outputs of one run are put in place together (OutputSet); a write that fails for want
// of space leaves the file as it was.

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

#include "tests/file_size_limit.h"

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

// Writes `text` to `path` as every writer does: to "<path>.partial", renamed into place.
void WriteThroughPartial(const fs::path& path, const std::string& text) {
  std::ofstream(path.string() + ".partial") << text;
  RenameInto(path.string() + ".partial", path.string());
}

TEST_F(FolderReplacementTest, AnOutputSetPutsItsOutputsInPlaceOnlyTogether) {
  Write(dir_ / "out.h5", "old out");
  Write(dir_ / "report.html", "old report");
  {
    OutputSet outputs({(dir_ / "out.h5").string(), (dir_ / "report.html").string()});
    WriteThroughPartial(dir_ / "out.h5", "new out");
    // Held back: the old file is still in place, the new one complete beside it.
    EXPECT_EQ(Contents(dir_).at("out.h5"), "old out");
    EXPECT_EQ(Contents(dir_).at("out.h5.partial"), "new out");
    // The second output fails: the set is never committed.
  }
  EXPECT_EQ(Contents(dir_), (std::map<std::string, std::string>{{"out.h5", "old out"},
                                                                {"report.html", "old report"}}));
  {
    OutputSet outputs({(dir_ / "out.h5").string(), (dir_ / "report.html").string(), ""});
    WriteThroughPartial(dir_ / "out.h5", "new out");
    WriteThroughPartial(dir_ / "report.html", "new report");
    EXPECT_EQ(Contents(dir_).at("report.html"), "old report");
    outputs.Commit();
  }
  EXPECT_EQ(Contents(dir_), (std::map<std::string, std::string>{{"out.h5", "new out"},
                                                                {"report.html", "new report"}}));
  {
    // A writer that fails half way leaves its partial: the set removes it.
    OutputSet outputs({(dir_ / "out.h5").string(), (dir_ / "report.html").string()});
    WriteThroughPartial(dir_ / "out.h5", "half a new out");
    std::ofstream((dir_ / "report.html.partial").string()) << "half a new report";
  }
  EXPECT_EQ(Contents(dir_), (std::map<std::string, std::string>{{"out.h5", "new out"},
                                                                {"report.html", "new report"}}));
  // Without a set, a rename happens at once; an output the set never saw written is skipped.
  WriteThroughPartial(dir_ / "out.h5", "newer out");
  EXPECT_EQ(Contents(dir_).at("out.h5"), "newer out");
  {
    OutputSet outputs({(dir_ / "out.h5").string(), (dir_ / "other.csv").string()});
    WriteThroughPartial(dir_ / "out.h5", "newest out");
    outputs.Commit();
  }
  EXPECT_EQ(Contents(dir_), (std::map<std::string, std::string>{{"out.h5", "newest out"},
                                                                {"report.html", "new report"}}));
}

TEST_F(FolderReplacementTest, AWriteThatRunsOutOfSpaceLeavesTheFileAsItWas) {
  Write(dir_ / "material.yaml", "the previous file");
  try {
    testing::FileSizeLimit limit(4096);
    WriteTextFile((dir_ / "material.yaml").string(), std::string(100000, 'x'));
    ADD_FAILURE() << "a write past the limit succeeded";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find((dir_ / "material.yaml").string() + ": cannot write"),
              std::string::npos)
        << e.what();
  }
  EXPECT_EQ(Contents(dir_),
            (std::map<std::string, std::string>{{"material.yaml", "the previous file"}}));
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
