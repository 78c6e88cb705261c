// The bad-input suite of `netlab label`: each row one kind of bad input, the exit
// status it must end in and what its message must name (tests/app/cli/bad_input.h). The fixture,
// a rendered shot of the small 6 x 6 net with its true labels as seeds, is made at run time.

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include "tests/app/cli/bad_input.h"
#include "tests/app/cli/h5_edit.h"
#include "tests/app/cli/small_shot.h"

namespace netlab::testing {
namespace {

class BadInputLabel : public CommandTest {
 protected:
  BadInputLabel() : CommandTest("bad_input_label") {}
  void SetUp() override {
    CommandTest::SetUp();
    std::ofstream(Path("scenario.yaml")) << kSmallShotScenario;
    ASSERT_EQ(
        RunNetlab("simulate " + Path("scenario.yaml") + " --out " + Path("sim.h5") + " --quiet")
            .status,
        0);
    ASSERT_EQ(RunNetlab("color-net --knots 6x6 --out " + Path("coloring.yaml") + " --quiet").status,
              0);
    ASSERT_EQ(
        RunNetlab("color-net --knots 5x5 --out " + Path("coloring5.yaml") + " --quiet").status, 0);
    const NetlabResult render = RunNetlab(
        "render --sim " + Path("sim.h5") + " --out " + Path("shot") +
        " --frames 0:2 --calibration-views 0 --coloring " + Path("coloring.yaml") + " --quiet");
    ASSERT_EQ(render.status, 0) << render.err;
    for (const char* name : {"far.h5", "inf.h5"})
      std::filesystem::copy_file(Path("shot/labels_true.h5"), Path(name));
    // Knot (0,0) of cam0's first frame: a seed far off the image, and one at infinity.
    PokeH5(Path("far.h5"), "/cameras/cam0/position_px", 0, -1e9);
    PokeH5(Path("far.h5"), "/cameras/cam0/position_px", 1, 5);
    PokeH5(Path("inf.h5"), "/cameras/cam0/position_px", 0, INFINITY);
    PokeH5(Path("inf.h5"), "/cameras/cam0/position_px", 1, 1e300);
    std::ofstream(Path("previous.h5")) << "the previous labels";
    std::ofstream(Path("previous.csv")) << "the previous table";
  }
};

TEST_F(BadInputLabel, EachKindEndsInAClearError) {
  const std::string inputs = "label {dir}/shot/experiment.yaml --rig {dir}/shot/rig_true.yaml ";
  const std::string base = inputs + "--coloring {dir}/coloring.yaml ";
  const std::string seeded = base + "--seed {dir}/shot/labels_true.h5 ";
  ExpectBadInputs(
      {
          {"a seed off the image",
           base + "--seed {dir}/far.h5 --out {dir}/l.h5",
           1,
           {"{dir}/far.h5", "camera cam0, frame 0, knot (0,0)", "(-1e+09, 5) is outside the"}},
          {"a seed at infinity",
           base + "--seed {dir}/inf.h5 --out {dir}/l.h5",
           1,
           {"{dir}/inf.h5", "/cameras/cam0/position_px", "not a position"}},
          {"missing seed file",
           base + "--seed {dir}/missing.h5 --out {dir}/l.h5",
           1,
           {"{dir}/missing.h5"}},
          {"the colouring of another net",
           inputs + "--coloring {dir}/coloring5.yaml --seed "
                    "{dir}/shot/labels_true.h5 --out {dir}/l.h5",
           1,
           {"{dir}/shot/labels_true.h5"}},
          {"missing colouring",
           inputs + "--coloring {dir}/missing.yaml --seed "
                    "{dir}/shot/labels_true.h5 --out {dir}/l.h5",
           1,
           {"{dir}/missing.yaml"}},
          {"missing rig",
           "label {dir}/shot/experiment.yaml --rig {dir}/missing.yaml --coloring "
           "{dir}/coloring.yaml --seed {dir}/shot/labels_true.h5 --out {dir}/l.h5",
           1,
           {"{dir}/missing.yaml"}},
          {"missing experiment",
           "label {dir}/missing.yaml --rig {dir}/shot/rig_true.yaml "
           "--coloring {dir}/coloring.yaml --seed {dir}/shot/labels_true.h5 "
           "--out {dir}/l.h5",
           1,
           {"{dir}/missing.yaml"}},
          {"frames outside the recording",
           seeded + "--frames 5:9 --out {dir}/l.h5",
           2,
           {"--frames 5:9", "outside"}},
          {"frames backwards", seeded + "--frames 2:1 --out {dir}/l.h5", 2, {"--frames"}},
          {"no --rig",
           "label {dir}/shot/experiment.yaml --coloring {dir}/coloring.yaml --seed "
           "{dir}/shot/labels_true.h5 --out {dir}/l.h5",
           2,
           {"--rig is required"}},
          {"empty --out", seeded + "--out ''", 2, {"--out needs a non-empty value"}},
          {"--out in a folder that is a file",
           seeded + "--out {dir}/coloring.yaml/l.h5",
           1,
           {"{dir}/coloring.yaml/l.h5"}},
          // An output over an input, another output or a special file.
          {"--out is the --seed file",
           seeded + "--out {dir}/shot/labels_true.h5",
           1,
           {"--out {dir}/shot/labels_true.h5", "the --seed file {dir}/shot/labels_true.h5"},
           {"{dir}/shot/labels_true.h5"}},
          {"--out is the --rig file",
           seeded + "--out {dir}/shot/rig_true.yaml",
           1,
           {"--out {dir}/shot/rig_true.yaml", "the --rig file"},
           {"{dir}/shot/rig_true.yaml"}},
          {"--xypts is --out",
           seeded + "--out {dir}/l.csv --xypts {dir}/l.csv",
           1,
           {"--xypts {dir}/l.csv", "is also --out {dir}/l.csv"}},
          {"--xypts in a folder that does not exist",
           seeded + "--out {dir}/previous.h5 --xypts {dir}/no/such/x.csv",
           1,
           {"--xypts {dir}/no/such/x.csv", "does not exist"},
           {"{dir}/previous.h5"}},
          // A full disk (a file size limit of 4 KiB): the labels and the table are left as they
          // were, no partial file beside them.
          {"a full disk",
           seeded + "--out {dir}/previous.h5",
           1,
           {"{dir}/previous.h5", "is the disk full?"},
           {"{dir}/previous.h5"},
           4096},
          {"a full disk, with --xypts",
           seeded + "--out {dir}/previous.h5 --xypts {dir}/previous.csv",
           1,
           {"{dir}/previous.", "is the disk full?"},
           {"{dir}/previous.h5", "{dir}/previous.csv"},
           4096},
      },
      dir_.string());
  EXPECT_FALSE(std::filesystem::exists(dir_ / "l.h5"));
  EXPECT_FALSE(std::filesystem::exists(dir_ / "l.h5.partial"));
}

}  // namespace
}  // namespace netlab::testing
