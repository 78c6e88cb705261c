// The bad-input suite of `netlab gui PROJECT` (tests/app/cli/bad_input.h): project files that are
// not projects, each refused at once with the reason on stderr (no window to wait on), and a
// --screenshot that would land on the project file, refused with the file left as it was. The
// window runs on Qt's offscreen platform. tests/app/gui/main_window_test.cc holds the projects
// that need a recording (a rig or a labels folder that does not exist).

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include "tests/app/cli/bad_input.h"

namespace netlab::testing {
namespace {

class BadInputGui : public CommandTest {
 protected:
  BadInputGui() : CommandTest("bad_input_gui") {}
  void SetUp() override {
    CommandTest::SetUp();
    setenv("QT_QPA_PLATFORM", "offscreen", 0);
    Write("empty.yaml", "");
    Write("list.yaml", "- experiment\n- rig\n");
    Write("scalar.yaml", "netlab_project\n");
    Write("twice.yaml", "netlab_project: 1\nrig: rig.yaml\nrig: other.yaml\n");
    Write("tagged.yaml", "netlab_project: !!str 1\n");
    Write("two_documents.yaml", "netlab_project: 1\n---\nnetlab_project: 2\n");
    Write("syntax.yaml", "netlab_project: 1\nrig: [unclosed\n");
    std::filesystem::create_directory(Path("folder.yaml"));
    const std::string project =
        "netlab_project: 1\nexperiment: e.yaml\nrig: r.yaml\nlabels: l.h5\nnet: {rows: 2, cols: "
        "2}\n";
    Write("score_names.yaml", project + "scores: [score_sim.h5]\n");
    Write("score_typo.yaml",
          project + "scores:\n  - {simulation: sim.h5, score: score_sim.h5, reprot: r.html}\n");
    Write("fits_map.yaml", project + "fits: {fit: fit.yaml}\n");
  }
  void Write(const std::string& name, const std::string& text) {
    std::ofstream(Path(name)) << text;
  }
};

TEST_F(BadInputGui, EachKindEndsInAClearError) {
  const std::string shot = " --screenshot {dir}/shot.png";
  ExpectBadInputs(
      {
          // "--labels is required" used to answer an empty or list-shaped project.
          {"an empty project",
           "gui {dir}/empty.yaml" + shot,
           1,
           {"{dir}/empty.yaml is empty: not a netlab project"}},
          {"a list as the project",
           "gui {dir}/list.yaml" + shot,
           1,
           {"{dir}/list.yaml holds a list", "not a netlab project"}},
          {"a word as the project",
           "gui {dir}/scalar.yaml" + shot,
           1,
           {"{dir}/scalar.yaml", "not a netlab project"}},
          {"a key given twice",
           "gui {dir}/twice.yaml" + shot,
           1,
           {"{dir}/twice.yaml:3: rig: given twice, at lines 2 and 3"}},
          {"a tag on a value",
           "gui {dir}/tagged.yaml" + shot,
           1,
           {"{dir}/tagged.yaml:1: netlab_project: the tag '!!str'"}},
          {"a second document",
           "gui {dir}/two_documents.yaml" + shot,
           1,
           {"{dir}/two_documents.yaml:3: a second YAML document"}},
          {"not YAML", "gui {dir}/syntax.yaml" + shot, 1, {"{dir}/syntax.yaml", "YAML"}},
          {"a score named without its simulation",
           "gui {dir}/score_names.yaml" + shot,
           1,
           {"{dir}/score_names.yaml:6", "scores", "each entry needs simulation and score"}},
          {"a misspelt key of a score",
           "gui {dir}/score_typo.yaml" + shot,
           1,
           {"{dir}/score_typo.yaml", "reprot"}},
          {"fits as a map",
           "gui {dir}/fits_map.yaml" + shot,
           1,
           {"{dir}/fits_map.yaml:6", "fits", "a list of netlab fit files expected"}},
          {"a folder as the project", "gui {dir}/folder.yaml" + shot, 1, {"{dir}/folder.yaml"}},
          {"a missing project",
           "gui {dir}/missing.yaml" + shot,
           1,
           {"{dir}/missing.yaml", "cannot open"}},
          // The screenshot was written in place over the project (0 bytes left).
          {"--screenshot is the project file",
           "gui {dir}/twice.yaml --screenshot {dir}/twice.yaml",
           1,
           {"{dir}/twice.yaml"},
           {"{dir}/twice.yaml"}},
      },
      dir_.string());
  EXPECT_FALSE(std::filesystem::exists(Path("shot.png")));
  EXPECT_FALSE(std::filesystem::exists(Path("shot.png.partial")));
}

}  // namespace
}  // namespace netlab::testing
