// common/output_paths.h: an output that is an input (by name, through a link, a hard link or
// ".."), another output, a special file, or in a missing folder is refused with both named; the
// ordinary case passes. And RenameInto (common/files.h) never renames over a FIFO.

#include "common/output_paths.h"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>

#include "common/files.h"

namespace netlab {
namespace {

namespace fs = std::filesystem;

class OutputPathsTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("netlab_output_paths_" + std::to_string(getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_ / "sub");
    std::ofstream(Path("in.h5")) << "input";
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string Path(const std::string& name) const { return (dir_ / name).string(); }

  // The message CheckOutputPaths throws, or "" when it passes.
  static std::string Refusal(const std::vector<NamedPath>& inputs,
                             const std::vector<NamedPath>& outputs) {
    try {
      CheckOutputPaths(inputs, outputs);
    } catch (const std::runtime_error& e) {
      return e.what();
    }
    return "";
  }

  fs::path dir_;
};

TEST_F(OutputPathsTest, DistinctWritableOutputsPass) {
  EXPECT_EQ(
      Refusal({{"--in", Path("in.h5")}},
              {{"--out", Path("out.h5")}, {"--report", Path("sub/report.html")}, {"--csv", ""}}),
      "");
  std::ofstream(Path("out.h5")) << "a previous output";  // replaced, as before
  EXPECT_EQ(Refusal({{"--in", Path("in.h5")}}, {{"--out", Path("out.h5")}}), "");
}

TEST_F(OutputPathsTest, AnOutputThatIsAnInputIsRefusedWithBothNamed) {
  fs::create_symlink(Path("in.h5"), Path("link.h5"));
  fs::create_hard_link(Path("in.h5"), Path("hard.h5"));
  for (const std::string& out :
       {Path("in.h5"), Path("link.h5"), Path("hard.h5"), Path("sub/../in.h5")}) {
    const std::string message = Refusal({{"--in", Path("in.h5")}}, {{"--out", out}});
    EXPECT_NE(message.find("--out " + out), std::string::npos) << message;
    EXPECT_NE(message.find("is the --in file " + Path("in.h5")), std::string::npos) << message;
  }
  // The input is where the output's partial file goes first.
  std::ofstream(Path("x.h5.partial")) << "input";
  EXPECT_NE(Refusal({{"--in", Path("x.h5.partial")}}, {{"--out", Path("x.h5")}})
                .find("written first to " + Path("x.h5") + ".partial"),
            std::string::npos);
}

TEST_F(OutputPathsTest, TwoOutputsInOneFileAreRefused) {
  const std::string message =
      Refusal({}, {{"--out", Path("s.h5")}, {"--report", Path("sub/../s.h5")}});
  EXPECT_NE(message.find("--report " + Path("sub/../s.h5")), std::string::npos) << message;
  EXPECT_NE(message.find("is also --out " + Path("s.h5")), std::string::npos) << message;
}

TEST_F(OutputPathsTest, SpecialFilesAndMissingFoldersAreRefused) {
  ASSERT_EQ(mkfifo(Path("fifo").c_str(), 0644), 0);
  fs::create_symlink("/dev/null", Path("null"));
  EXPECT_NE(Refusal({}, {{"--out", Path("fifo")}}).find("a FIFO"), std::string::npos);
  EXPECT_NE(Refusal({}, {{"--out", Path("null")}}).find("a character device"), std::string::npos);
  EXPECT_NE(Refusal({}, {{"--out", Path("sub")}}).find("is a folder"), std::string::npos);
  const std::string missing =
      Refusal({}, {{"--out", Path("a.h5")}, {"--report", Path("no/such/r.html")}});
  EXPECT_NE(missing.find("--report " + Path("no/such/r.html") + ": the folder"), std::string::npos)
      << missing;
  EXPECT_NE(missing.find("does not exist"), std::string::npos) << missing;
  EXPECT_NE(Refusal({}, {{"--out", Path("in.h5/a.h5")}}).find("is not a folder"),
            std::string::npos);
}

TEST_F(OutputPathsTest, RenameIntoNeverReplacesAFifo) {
  ASSERT_EQ(mkfifo(Path("fifo").c_str(), 0644), 0);
  std::ofstream(Path("fifo.partial")) << "new";
  EXPECT_THROW(RenameInto(Path("fifo.partial"), Path("fifo")), std::runtime_error);
  EXPECT_TRUE(fs::is_fifo(Path("fifo")));
}

}  // namespace
}  // namespace netlab
