// The bad-input suite of `netlab simulate` and `netlab sweep` (issue 21): each row one kind of bad
// input a new user could give, the exit status it must end in and what its message must name
// (tests/app/cli/bad_input.h). The fixtures are written at run time.

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "tests/app/cli/bad_input.h"
#include "tests/app/cli/small_shot.h"

namespace netlab::testing {
namespace {

class BadInputSimulate : public CommandTest {
 protected:
  BadInputSimulate() : CommandTest("bad_input_simulate") {}
  void SetUp() override {
    CommandTest::SetUp();
    Write("scene.yaml", kSmallShotScenario);
    Write("empty.yaml", "");
    Write("truncated.yaml", std::string(kSmallShotScenario).substr(0, 200));
    Write("not_yaml.yaml", "name: [unclosed\n  - {");
    Write("nan.yaml",
          Replace(kSmallShotScenario, "stretch_stiffness: 1571", "stretch_stiffness: .nan"));
    Write("negative.yaml",
          Replace(kSmallShotScenario, "linear_density: 8.95e-4", "linear_density: -8.95e-4"));
    Write("wrong_type.yaml", Replace(kSmallShotScenario, "knots: [6, 6]", "knots: three"));
    Write("huge_net.yaml", Replace(kSmallShotScenario, "knots: [6, 6]", "knots: [40000, 40000]"));
    Write("stiff.yaml",
          Replace(kSmallShotScenario, "stretch_stiffness: 1571", "stretch_stiffness: 1e300"));
  }
  void Write(const std::string& name, const std::string& text) { std::ofstream(Path(name)) << text; }
  static std::string Replace(std::string text, const std::string& from, const std::string& to) {
    text.replace(text.find(from), from.size(), to);
    return text;
  }
};

TEST_F(BadInputSimulate, EachKindEndsInAClearError) {
  ExpectBadInputs(
      {
          {"no scenario", "simulate --out {dir}/a.h5", 2, {"expected one SCENARIO.yaml"}},
          {"missing file",
           "simulate {dir}/missing.yaml --out {dir}/a.h5",
           1,
           {"{dir}/missing.yaml", "cannot open"}},
          {"empty file", "simulate {dir}/empty.yaml --out {dir}/a.h5", 1, {"{dir}/empty.yaml"}},
          {"truncated file",
           "simulate {dir}/truncated.yaml --out {dir}/a.h5",
           1,
           {"{dir}/truncated.yaml"}},
          {"not YAML",
           "simulate {dir}/not_yaml.yaml --out {dir}/a.h5",
           1,
           {"{dir}/not_yaml.yaml:"}},
          {"NaN",
           "simulate {dir}/nan.yaml --out {dir}/a.h5",
           1,
           {"{dir}/nan.yaml:", "materials.nylon.stretch_stiffness"}},
          {"negative",
           "simulate {dir}/negative.yaml --out {dir}/a.h5",
           1,
           {"{dir}/negative.yaml:", "materials.nylon.linear_density", "> 0"}},
          {"wrong type",
           "simulate {dir}/wrong_type.yaml --out {dir}/a.h5",
           1,
           {"{dir}/wrong_type.yaml:", "nets[0].knots", "integers"}},
          {"a net past the model's indices",
           "simulate {dir}/huge_net.yaml --out {dir}/a.h5",
           1,
           {"{dir}/huge_net.yaml", "nets.0 ('net'): 40000x40000 knots", "it can index"}},
          {"a net past the memory",
           "simulate {dir}/scene.yaml --out {dir}/a.h5 --set "
           "'nets.0.knots=[20000,2000]'",
           1,
           {"{dir}/scene.yaml", "nets.0 ('net'): 20000x2000 knots", "available"}},
          {"a step that never ends",
           "simulate {dir}/stiff.yaml --out {dir}/a.h5",
           1,
           {"{dir}/stiff.yaml", "dt", "steps", "stiffness"}},
          {"unknown --set path",
           "simulate {dir}/scene.yaml --out {dir}/a.h5 --set nets.0.knotz=3",
           1,
           {"nets.0.knotz"}},
          {"--set value of the wrong kind",
           "simulate {dir}/scene.yaml --out {dir}/a.h5 --set duration=long",
           1,
           {"duration"}},
          {"--set without a value",
           "simulate {dir}/scene.yaml --out {dir}/a.h5 --set duration",
           2,
           {"--set"}},
          {"out-of-range --duration",
           "simulate {dir}/scene.yaml --out {dir}/a.h5 --duration -1",
           2,
           {"--duration"}},
          {"empty --out",
           "simulate {dir}/scene.yaml --out ''",
           2,
           {"--out needs a non-empty value"}},
          {"--out in a folder that is a file",
           "simulate {dir}/scene.yaml --out {dir}/scene.yaml/a.h5",
           1,
           {"{dir}/scene.yaml/a.h5"}},
          {"unknown option",
           "simulate {dir}/scene.yaml --out {dir}/a.h5 --bogus",
           2,
           {"unknown option --bogus"}},
      },
      dir_.string());
  // Nothing was written under the outputs' names, and no partial file was left.
  EXPECT_FALSE(std::filesystem::exists(dir_ / "a.h5"));
  EXPECT_FALSE(std::filesystem::exists(dir_ / "a.h5.partial"));
  EXPECT_FALSE(std::filesystem::exists(".partial"));
}

TEST_F(BadInputSimulate, SweepEndsInAClearError) {
  ExpectBadInputs(
      {
          {"no --vary", "sweep {dir}/scene.yaml --out {dir}/s.h5", 2, {"--vary"}},
          {"--vary without a range", "sweep {dir}/scene.yaml --vary duration --out {dir}/s.h5",
           2, {"--vary", "PATH=a:b:n"}},
          {"--vary of an unknown path",
           "sweep {dir}/scene.yaml --vary nets.0.knotz=1:2:2 --out {dir}/s.h5", 1,
           {"{dir}/scene.yaml", "knotz", "unknown key"}},
          {"--vary with n = 0",
           "sweep {dir}/scene.yaml --vary drag.drag_coefficient=1:2:0 --out {dir}/s.h5", 2,
           {"--vary"}},
          {"missing scenario", "sweep {dir}/missing.yaml --vary duration=0.01:0.02:2 --out "
                               "{dir}/s.h5", 1, {"{dir}/missing.yaml"}},
          {"empty --out", "sweep {dir}/scene.yaml --vary duration=0.01:0.02:2 --out ''", 2,
           {"--out needs a non-empty value"}},
          {"empty --report",
           "sweep {dir}/scene.yaml --vary duration=0.01:0.02:2 --out {dir}/s.h5 --report ''", 2,
           {"--report needs a non-empty value"}},
          {"out-of-range --jobs",
           "sweep {dir}/scene.yaml --vary duration=0.01:0.02:2 --out {dir}/s.h5 --jobs 0", 2,
           {"--jobs"}},
      },
      dir_.string());
  EXPECT_FALSE(std::filesystem::exists(dir_ / "s.h5"));
  EXPECT_FALSE(std::filesystem::exists(dir_ / "s.h5.partial"));
  // Every run rejecting its value is an error, not a study: the file still says why.
  ExpectBadInput({"every run's value rejected",
                  "sweep {dir}/scene.yaml --vary materials.nylon.linear_density=-2:-1:2 --out "
                  "{dir}/s.h5 --quiet",
                  1,
                  {"run 0", "materials.nylon.linear_density", "all 2 runs failed", "{dir}/s.h5"}},
                 dir_.string());
}

}  // namespace
}  // namespace netlab::testing
