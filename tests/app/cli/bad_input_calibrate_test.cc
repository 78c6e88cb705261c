// The bad-input suite of `netlab calibrate`: each row one kind of bad input, the exit
// status it must end in and what its message must name (tests/app/cli/bad_input.h). The images
// are written at run time: blank ones (no board in them), a text file named .png, a truncated
// PNG.

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <string>

#include "tests/app/cli/bad_input.h"

namespace netlab::testing {
namespace {

class BadInputCalibrate : public CommandTest {
 protected:
  BadInputCalibrate() : CommandTest("bad_input_calibrate") {}
  void SetUp() override {
    CommandTest::SetUp();
    for (const char* folder : {"blank", "text", "truncated"})
      std::filesystem::create_directories(dir_ / folder);
    const cv::Mat blank(120, 160, CV_8UC1, cv::Scalar(128));
    for (int i = 0; i < 3; ++i) {
      cv::imwrite(Path("blank/frame_" + std::to_string(i) + ".png"), blank);
      cv::imwrite(Path("truncated/frame_" + std::to_string(i) + ".png"), blank);
    }
    std::ofstream(Path("text/frame_0.png")) << "this is not a PNG\n";
    std::filesystem::resize_file(Path("truncated/frame_1.png"), 40);
    std::ofstream(Path("board.yaml")) << "board: {type: chessboard, cols: [9\n";
  }
};

TEST_F(BadInputCalibrate, EachKindEndsInAClearError) {
  const std::string board = "calibrate --board chessboard:9x6:0.06 ";
  ExpectBadInputs(
      {
          {"no --board",
           "calibrate --images cam0='{dir}/blank/*.png' --out {dir}/rig.yaml",
           2,
           {"--board"}},
          {"a board spec with a typo",
           "calibrate --board chessbord:9x6:0.06 --images "
           "cam0='{dir}/blank/*.png' --out {dir}/rig.yaml",
           1,
           {"chessbord"}},
          {"a board with a negative square",
           "calibrate --board chessboard:9x6:-0.06 --images "
           "cam0='{dir}/blank/*.png' --out {dir}/rig.yaml",
           1,
           {"SQUARE", "-0.06"}},
          {"a broken board file",
           "calibrate --board {dir}/board.yaml --images "
           "cam0='{dir}/blank/*.png' --out {dir}/rig.yaml",
           1,
           {"{dir}/board.yaml"}},
          {"--images without a camera name",
           board + "--images '{dir}/blank/*.png' --out "
                   "{dir}/rig.yaml",
           2,
           {"--images"}},
          {"a glob that matches nothing",
           board + "--images cam0='{dir}/none/*.png' --out "
                   "{dir}/rig.yaml",
           1,
           {"{dir}/none/*.png"}},
          {"a text file named .png",
           board + "--images cam0='{dir}/text/*.png' --out "
                   "{dir}/rig.yaml",
           1,
           {"{dir}/text/frame_0.png"}},
          {"a truncated PNG",
           board + "--images cam0='{dir}/truncated/*.png' --out "
                   "{dir}/rig.yaml",
           1,
           {"{dir}/truncated/frame_1.png", "truncated PNG"}},
          {"no board in any image",
           board + "--images cam0='{dir}/blank/*.png' --out "
                   "{dir}/rig.yaml",
           1,
           {"cam0"}},
          {"a missing --fix-intrinsics",
           board + "--images cam0='{dir}/blank/*.png' --out "
                   "{dir}/rig.yaml --fix-intrinsics "
                   "{dir}/missing.yaml",
           1,
           {"{dir}/missing.yaml"}},
          {"empty --out",
           board + "--images cam0='{dir}/blank/*.png' --out ''",
           2,
           {"--out needs a non-empty value"}},
          // The rig over one of the run's inputs.
          {"--out is the --fix-intrinsics file",
           board + "--images cam0='{dir}/blank/*.png' --out {dir}/board.yaml --fix-intrinsics "
                   "{dir}/board.yaml",
           1,
           {"--out {dir}/board.yaml", "the --fix-intrinsics file {dir}/board.yaml"},
           {"{dir}/board.yaml"}},
          {"--out is an image",
           board + "--images cam0='{dir}/blank/*.png' --out "
                   "{dir}/blank/frame_0.png",
           1,
           {"--out {dir}/blank/frame_0.png", "the --images cam0 file"},
           {"{dir}/blank/frame_0.png"}},
      },
      dir_.string());
  EXPECT_FALSE(std::filesystem::exists(dir_ / "rig.yaml"));
  EXPECT_FALSE(std::filesystem::exists(dir_ / "rig.yaml.partial"));
}

}  // namespace
}  // namespace netlab::testing
