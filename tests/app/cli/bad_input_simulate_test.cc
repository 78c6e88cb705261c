// The bad-input suite of `netlab simulate` and `netlab sweep`: each row one kind of bad
// input a new user could give, the exit status it must end in and what its message must name
// (tests/app/cli/bad_input.h). The fixtures are written at run time.

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <chrono>
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
    // An output frame every 1e-12 s (the step shrinks to divide it: 6e10 steps and frames), and
    // every 1e-9 s over a 6 s flight: each ran for days, filling the disk.
    Write("dense.yaml", Replace(kSmallShotScenario, "output_interval: 0.005586592178770949",
                                "output_interval: 1e-12"));
    Write("dense_flight.yaml",
          Replace(Replace(kSmallShotScenario, "output_interval: 0.005586592178770949",
                          "output_interval: 1e-9"),
                  "duration: 0.06", "duration: 6"));
    // What a YAML reader takes without a word and netlab would misread.
    Write("twice.yaml", std::string(kSmallShotScenario) + "duration: -3\n");
    Write("materials_twice.yaml",
          std::string(kSmallShotScenario) + "materials:\n  nylon: {diameter: 1.0e-3}\n");
    Write("tagged.yaml", Replace(kSmallShotScenario, "duration: 0.06", "duration: !!str 0.06"));
    Write("custom_tag.yaml",
          Replace(kSmallShotScenario, "duration: 0.06", "duration: !seconds 0.06"));
    Write("two_documents.yaml", std::string(kSmallShotScenario) + "---\nduration: 5\n");
    std::filesystem::create_directory(Path("folder.yaml"));
    Write("gravity_folder.yaml", Replace(kSmallShotScenario, "gravity: [0, 0, 0]",
                                         "gravity: {file: " + Path("folder.yaml") + "}"));
    Write("gravity_zero.yaml",
          Replace(kSmallShotScenario, "gravity: [0, 0, 0]", "gravity: {file: /dev/zero}"));
    std::ofstream(Path("previous.h5")) << "the previous output";
    std::filesystem::create_symlink(Path("scene.yaml"), Path("link_to_scene.h5"));
    mkfifo(Path("fifo").c_str(), 0644);
  }
  void Write(const std::string& name, const std::string& text) {
    std::ofstream(Path(name)) << text;
  }
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
          // A stiffness past any cord: the explicit step would never end, the implicit one ran
          // with an elastic energy of 7e273 J and called itself stable.
          {"a stiffness of 1e300 N",
           "simulate {dir}/stiff.yaml --out {dir}/a.h5",
           1,
           {"{dir}/stiff.yaml:", "materials.nylon.stretch_stiffness: 1e+300 N",
            "stiffer than any cord"}},
          {"a stiffness of 1e300 N under the implicit step",
           "simulate {dir}/scene.yaml --out {dir}/a.h5 --set integrator.type=implicit --set "
           "materials.nylon.stretch_stiffness=1e300",
           1,
           {"{dir}/scene.yaml:", "materials.nylon.stretch_stiffness: 1e+300 N", "at most 1e+12"}},
          {"a bending stiffness of 2e12 N m^2",
           "simulate {dir}/scene.yaml --out {dir}/a.h5 --set materials.nylon.bend_stiffness=2e12",
           1,
           {"materials.nylon.bend_stiffness: 2e+12 N m^2", "stiffer than any cord"}},
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
          // A value of a hundred thousand digits is quoted by its start and its length, not
          // echoed whole (AHugeValueGivesAOneLineMessage below checks the message's length).
          {"a number of a hundred thousand digits",
           "simulate {dir}/scene.yaml --out {dir}/a.h5 --duration " + std::string(100000, '9'),
           2,
           {"--duration expects a number",
            "'9999999999999999999999999999999999999999... (100000 "
            "characters)'"}},
          {"--set with a value of a hundred thousand digits",
           "simulate {dir}/scene.yaml --out {dir}/a.h5 --set drag.coefficient=" +
               std::string(100000, '9'),
           1,
           {"drag.coefficient: unknown key", "(100017 characters)"}},
          // An output over an input, another output or a special file.
          {"--out is the scenario",
           "simulate {dir}/scene.yaml --out {dir}/scene.yaml",
           1,
           {"--out {dir}/scene.yaml", "the scenario file {dir}/scene.yaml"},
           {"{dir}/scene.yaml"}},
          {"--out is a link to the scenario",
           "simulate {dir}/scene.yaml --out {dir}/link_to_scene.h5",
           1,
           {"--out {dir}/link_to_scene.h5", "the scenario file {dir}/scene.yaml"},
           {"{dir}/scene.yaml", "{dir}/link_to_scene.h5"}},
          {"--out is a FIFO",
           "simulate {dir}/scene.yaml --out {dir}/fifo",
           1,
           {"--out {dir}/fifo", "a FIFO", "not a regular file"},
           {"{dir}/fifo"}},
          {"segments so short the step never ends",
           "simulate {dir}/scene.yaml --out {dir}/a.h5 --set nets.0.segments_per_link=2000",
           1,
           {"{dir}/scene.yaml: dt", "nets.0.segments_per_link 2000 (segments of 5e-05 m)"}},
          // 6e6 segments: the step names the key (it built a 15.5 GB model for 50 s and then
          // spoke of the output's size).
          {"a hundred thousand segments per link",
           "simulate {dir}/scene.yaml --out {dir}/a.h5 --set nets.0.segments_per_link=100000",
           1,
           {"{dir}/scene.yaml: dt", "nets.0.segments_per_link 100000 (segments of 1e-06 m)"}},
          {"a step longer than the run",
           "simulate {dir}/scene.yaml --out {dir}/a.h5 --set integrator.dt=10",
           1,
           {"{dir}/scene.yaml: integrator.dt 10 s is longer than the duration 0.06 s", "no step"}},
          {"a key given twice",
           "simulate {dir}/twice.yaml --out {dir}/previous.h5",
           1,
           {"{dir}/twice.yaml:15: duration: given twice, at lines 2 and 15", "keep one"},
           {"{dir}/previous.h5"}},
          {"a section given twice",
           "simulate {dir}/materials_twice.yaml --out {dir}/a.h5",
           1,
           {"{dir}/materials_twice.yaml:15: materials: given twice, at lines 6 and 15"}},
          {"a tag on a number",
           "simulate {dir}/tagged.yaml --out {dir}/a.h5",
           1,
           {"{dir}/tagged.yaml:2: duration: the tag '!!str' is not read by netlab"}},
          {"a custom tag on a number",
           "simulate {dir}/custom_tag.yaml --out {dir}/a.h5",
           1,
           {"{dir}/custom_tag.yaml:2: duration: the tag '!seconds'"}},
          {"a second document",
           "simulate {dir}/two_documents.yaml --out {dir}/a.h5",
           1,
           {"{dir}/two_documents.yaml:16: a second YAML document", "one document per file"}},
          {"a folder as the scenario",
           "simulate {dir}/folder.yaml --out {dir}/a.h5",
           1,
           {"{dir}/folder.yaml: is a folder, not a YAML scenario file"}},
          {"a folder as a time series",
           "simulate {dir}/gravity_folder.yaml --out {dir}/a.h5",
           1,
           {"{dir}/gravity_folder.yaml:5: gravity.file: {dir}/folder.yaml: is a folder, not a "
            "CSV time series"}},
          {"a device as a time series",
           "simulate {dir}/gravity_zero.yaml --out {dir}/a.h5",
           1,
           {"{dir}/gravity_zero.yaml:5: gravity.file: /dev/zero: not a regular file"}},
          {"a device as the scenario",
           "simulate /dev/zero --out {dir}/a.h5",
           1,
           {"/dev/zero: more than 64 MiB"}},
          {"a --set value with a key twice",
           "simulate {dir}/scene.yaml --out {dir}/a.h5 --set 'integrator={type: explicit, type: "
           "implicit}'",
           1,
           {"{dir}/scene.yaml: --set integrator=", "type: given twice"}},
          {"an alias bomb in a --set value",
           "simulate {dir}/scene.yaml --out {dir}/a.h5 --set 'gravity=[&a [1,1,1,1,1,1,1,1], &b "
           "[*a,*a,*a,*a,*a,*a,*a,*a], &c [*b,*b,*b,*b,*b,*b,*b,*b], &d "
           "[*c,*c,*c,*c,*c,*c,*c,*c], &e [*d,*d,*d,*d,*d,*d,*d,*d], &f "
           "[*e,*e,*e,*e,*e,*e,*e,*e], &g [*f,*f,*f,*f,*f,*f,*f,*f], "
           "[*g,*g,*g,*g,*g,*g,*g,*g]]'",
           1,
           {"{dir}/scene.yaml: --set gravity=", "aliases", "expand to more values"}},
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
          {"--vary without a range",
           "sweep {dir}/scene.yaml --vary duration --out {dir}/s.h5",
           2,
           {"--vary", "PATH=a:b:n"}},
          {"--vary of an unknown path",
           "sweep {dir}/scene.yaml --vary nets.0.knotz=1:2:2 --out {dir}/s.h5",
           1,
           {"{dir}/scene.yaml", "knotz", "unknown key"}},
          {"--vary with n = 0",
           "sweep {dir}/scene.yaml --vary drag.drag_coefficient=1:2:0 --out {dir}/s.h5",
           2,
           {"--vary"}},
          {"missing scenario",
           "sweep {dir}/missing.yaml --vary duration=0.01:0.02:2 --out "
           "{dir}/s.h5",
           1,
           {"{dir}/missing.yaml"}},
          {"empty --out",
           "sweep {dir}/scene.yaml --vary duration=0.01:0.02:2 --out ''",
           2,
           {"--out needs a non-empty value"}},
          {"empty --report",
           "sweep {dir}/scene.yaml --vary duration=0.01:0.02:2 --out {dir}/s.h5 --report ''",
           2,
           {"--report needs a non-empty value"}},
          {"out-of-range --jobs",
           "sweep {dir}/scene.yaml --vary duration=0.01:0.02:2 --out {dir}/s.h5 --jobs 0",
           2,
           {"--jobs"}},
          // An output over an input, another output or a special file.
          {"--out is the scenario",
           "sweep {dir}/scene.yaml --vary duration=0.01:0.02:2 --out {dir}/scene.yaml",
           1,
           {"--out {dir}/scene.yaml", "the scenario file {dir}/scene.yaml"},
           {"{dir}/scene.yaml"}},
          {"--report is --out",
           "sweep {dir}/scene.yaml --vary duration=0.01:0.02:2 --out {dir}/previous.h5 --report "
           "{dir}/previous.h5",
           1,
           {"--report {dir}/previous.h5", "is also --out {dir}/previous.h5"},
           {"{dir}/previous.h5"}},
          {"--report in a folder that does not exist",
           "sweep {dir}/scene.yaml --vary duration=0.01:0.02:2 --out {dir}/previous.h5 --report "
           "{dir}/no/such/r.html",
           1,
           {"--report {dir}/no/such/r.html", "does not exist", "nothing was written"},
           {"{dir}/previous.h5"}},
      },
      dir_.string());
  EXPECT_FALSE(std::filesystem::exists(dir_ / "s.h5"));
  EXPECT_FALSE(std::filesystem::exists(dir_ / "s.h5.partial"));
  // Every run rejecting its value is an error, not a study: each run's error is named, and
  // nothing is written; an existing output and report are left as they were.
  std::ofstream(Path("previous.html")) << "the previous report";
  ExpectBadInputs({{"every run's value rejected",
                    "sweep {dir}/scene.yaml --vary materials.nylon.linear_density=-2:-1:2 --out "
                    "{dir}/s.h5 --quiet",
                    1,
                    {"run 0", "materials.nylon.linear_density", "all 2 runs failed",
                     "{dir}/s.h5 was not written"},
                    {"{dir}/s.h5"}},
                   {"every run's value rejected, over an existing output",
                    "sweep {dir}/scene.yaml --vary materials.nylon.linear_density=-2:-1:2 --out "
                    "{dir}/previous.h5 --report {dir}/previous.html --quiet",
                    1,
                    {"run 1", "all 2 runs failed",
                     "{dir}/previous.h5 was not written, the "
                     "existing file is as it was"},
                    {"{dir}/previous.h5", "{dir}/previous.html"}}},
                  dir_.string());
  EXPECT_FALSE(std::filesystem::exists(dir_ / "s.h5.partial"));
  EXPECT_FALSE(std::filesystem::exists(dir_ / "previous.h5.partial"));
  EXPECT_FALSE(std::filesystem::exists(dir_ / "previous.html.partial"));
}

// A disk that fills while the output is written (a file-size limit stands in for it): the run
// ends in exit 1 naming the output, the previous output is left byte for byte and no partial
// file stays beside it; a sweep's --out and --report alike.
TEST_F(BadInputSimulate, AFullDiskLeavesThePreviousOutput) {
  std::ofstream(Path("previous.html")) << "the previous report";
  ExpectBadInputs(
      {
          {"simulate onto a full disk",
           "simulate {dir}/scene.yaml --out {dir}/previous.h5 --quiet",
           1,
           {"{dir}/previous.h5: writing {dir}/previous.h5.partial failed (is the disk full?)"},
           {"{dir}/previous.h5"},
           4096},
          {"sweep onto a full disk",
           "sweep {dir}/scene.yaml --vary duration=0.01:0.02:2 --out {dir}/previous.h5 --report "
           "{dir}/previous.html --quiet",
           1,
           {"{dir}/previous.", "is the disk full?"},
           {"{dir}/previous.h5", "{dir}/previous.html"},
           4096},
          {"sweep without a report onto a full disk",
           "sweep {dir}/scene.yaml --vary duration=0.01:0.02:2 --out {dir}/previous.h5 --quiet",
           1,
           {"{dir}/previous.h5: writing {dir}/previous.h5.partial failed (is the disk full?)"},
           {"{dir}/previous.h5"},
           4096},
      },
      dir_.string());
}

// An output_interval that asks for more frames than the disk (simulate) or the memory (sweep,
// which keeps each run's tracks) holds is refused before the first step, naming the key and the
// size: these ran for days.
// A value a hundred thousand characters long (a paste gone wrong) is named by its start and its
// length: the message stays a line or two, whichever option or --set carries it.
TEST_F(BadInputSimulate, AHugeValueGivesAOneLineMessage) {
  const std::string huge(100000, '9');
  for (const std::string& args : {"--duration " + huge, "--set duration=" + huge,
                                  "--set drag.coefficient=" + huge, "--set " + huge, "--" + huge}) {
    SCOPED_TRACE(args.substr(0, 30));
    const NetlabResult r =
        RunNetlab("simulate " + Path("scene.yaml") + " --out " + Path("a.h5") + " " + args);
    EXPECT_NE(r.status, 0);
    EXPECT_NE(r.err.find("(1000"), std::string::npos) << r.err.substr(0, 300);
    EXPECT_LT(r.err.size(), 600u) << r.err.substr(0, 300);
  }
}

TEST_F(BadInputSimulate, AnOutputTooLargeIsRefusedBeforeAnyStep) {
  const auto start = std::chrono::steady_clock::now();
  ExpectBadInputs(
      {
          {"a frame every 1e-12 s",
           "simulate {dir}/dense.yaml --out {dir}/previous.h5",
           1,
           {"{dir}/dense.yaml", "output_interval 1e-12 s", "6e+10 output frames",
            "TB in "
            "{dir}/previous.h5",
            "free there"},
           {"{dir}/previous.h5"}},
          {"a frame every 1e-9 s of a 6 s flight",
           "simulate {dir}/dense_flight.yaml --out {dir}/a.h5",
           1,
           {"{dir}/dense_flight.yaml", "output_interval 1e-09 s", "6e+09 output frames", "TB"}},
          {"a sweep of frames every 1e-12 s",
           "sweep {dir}/dense.yaml --vary duration=0.05:0.06:2 --out {dir}/dense_sweep.h5 --quiet",
           1,
           {"run 0", "output_interval 1e-12 s", "output frames", "in memory", "available",
            "all 2 runs failed"}},
          {"a sweep of frames every 1e-9 s of a 6 s flight",
           "sweep {dir}/dense_flight.yaml --vary nets.0.velocity.0=0.4:0.6:2 --out "
           "{dir}/dense_sweep.h5 --quiet",
           1,
           {"run 1", "output_interval 1e-09 s", "6e+09 output frames", "in memory"}},
      },
      dir_.string());
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 60.0);
  EXPECT_FALSE(std::filesystem::exists(dir_ / "a.h5"));
  EXPECT_FALSE(std::filesystem::exists(dir_ / "a.h5.partial"));
  EXPECT_FALSE(std::filesystem::exists(dir_ / "previous.h5.partial"));
}

}  // namespace
}  // namespace netlab::testing
