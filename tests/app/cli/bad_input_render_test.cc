// The bad-input suite of `netlab render`: every kind of bad input ends in a message
// naming the file and the key or frame, and a render never loses the shot it replaces: the whole
// folder is written as DIR.partial and put in place of DIR only when complete.

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "tests/app/cli/bad_input.h"
#include "tests/app/cli/h5_edit.h"
#include "tests/app/cli/run_netlab.h"
#include "tests/app/cli/small_shot.h"

namespace netlab::testing {
namespace {

namespace fs = std::filesystem;

// The small shot's simulation's stored frames are 0.0056 s apart: frame 3 is at 0.0168 s.
constexpr int kNanFrame = 3;
// A quick render: 256 x 256 images, no calibration images, four camera frames.
constexpr char kQuick[] = " --scale 0.125 --calibration-views 0 --quiet";

class BadInputRender : public CommandTest {
 protected:
  BadInputRender() : CommandTest("bad_input_render") {}

  // `netlab simulate` of the small shot into `name`, with `set` options.
  std::string Simulate(const std::string& name, const std::string& set = "") {
    if (!fs::exists(Path("scenario.yaml")))
      std::ofstream(Path("scenario.yaml")) << kSmallShotScenario;
    const NetlabResult r =
        RunNetlab("simulate " + Path("scenario.yaml") + " --out " + Path(name) + set + " --quiet");
    EXPECT_EQ(r.status, 0) << r.err;
    return Path(name);
  }
  NetlabResult Render(const std::string& sim, const std::string& out,
                      const std::string& options = " --frames 0:3") {
    return RunNetlab("render --sim " + sim + " --out " + out + options + kQuick);
  }
  // A copy of `sim` with node 0 not finite at stored frame kNanFrame.
  std::string NanCopy(const std::string& sim, const std::string& name) {
    fs::copy_file(sim, Path(name));
    EditDataset<double>(Path(name), "nodes/position", H5T_NATIVE_DOUBLE,
                        [](std::vector<double>& x, std::vector<hsize_t>& dims) {
                          x[kNanFrame * dims[1] * 3] = std::numeric_limits<double>::quiet_NaN();
                        });
    return Path(name);
  }

  // Every file under `folder`, relative path -> content.
  static std::map<std::string, std::string> Contents(const fs::path& folder) {
    std::map<std::string, std::string> files;
    for (const auto& entry : fs::recursive_directory_iterator(folder)) {
      if (!entry.is_regular_file()) continue;
      std::stringstream bytes;
      bytes << std::ifstream(entry.path(), std::ios::binary).rdbuf();
      files[fs::relative(entry.path(), folder).string()] = bytes.str();
    }
    return files;
  }
  // The names in the scratch folder that start with `prefix` (shot, shot.partial, shot.old.*).
  std::vector<std::string> Named(const std::string& prefix) const {
    std::vector<std::string> names;
    for (const auto& entry : fs::directory_iterator(dir_))
      if (entry.path().filename().string().rfind(prefix, 0) == 0)
        names.push_back(entry.path().filename().string());
    std::sort(names.begin(), names.end());
    return names;
  }
};

TEST_F(BadInputRender, EveryBadInputIsNamed) {
  const std::string sim = Simulate("sim.h5");
  NanCopy(sim, "simnan.h5");
  std::ofstream(Path("empty.h5")).close();
  {
    std::ifstream in(sim, std::ios::binary);
    std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    std::ofstream(Path("cut.h5"), std::ios::binary) << bytes.substr(0, bytes.size() / 2);
  }
  std::ofstream(Path("text.h5")) << "this is a scenario, not a result\n";
  std::ofstream(Path("file")) << "a file where the output folder goes\n";
  std::ofstream(Path("badrig.yaml")) << "%YAML:1.0\n---\ncameras: 3\n";
  ASSERT_EQ(RunNetlab("color-net --knots 5x5 --out " + Path("col5.yaml") + " --quiet").status, 0);
  fs::create_directories(Path("inside"));
  fs::copy_file(sim, Path("inside/sim.h5"));
  // A simulation without /nodes: the knot tracks a render writes as its truth.
  ASSERT_EQ(Render(sim, Path("shot")).status, 0);

  const std::string render = "render --sim ";
  const std::string out = " --out {dir}/o" + std::string(kQuick);
  ExpectBadInputs(
      {
          {"missing simulation", render + "{dir}/missing.h5" + out, 1, {"{dir}/missing.h5"}},
          {"empty simulation", render + "{dir}/empty.h5" + out, 1, {"{dir}/empty.h5"}},
          {"truncated simulation", render + "{dir}/cut.h5" + out, 1, {"{dir}/cut.h5"}},
          {"text as simulation", render + "{dir}/text.h5" + out, 1, {"{dir}/text.h5"}},
          {"knot tracks without /nodes",
           render + "{dir}/shot/truth.h5" + out,
           1,
           {"{dir}/shot/truth.h5", "/nodes/position"}},
          {"a NaN node (U4)",
           render + "{dir}/simnan.h5" + out,
           1,
           {"{dir}/simnan.h5: /nodes/position is not finite at frame 3 (t = 0.0167",
            "node 0 (net 'net' knot (0,0))"}},
          {"frames beyond the simulation",
           render + "{dir}/sim.h5 --frames 0:500" + out,
           1,
           {"frames 0:500", "0:10"}},
          {"--frames backwards", render + "{dir}/sim.h5 --frames 5:2" + out, 2, {"--frames"}},
          {"--scale 0", render + "{dir}/sim.h5 --scale 0 --out {dir}/o", 2, {"--scale"}},
          {"--scale not a number",
           render + "{dir}/sim.h5 --scale half --out {dir}/o",
           2,
           {"--scale", "half"}},
          {"--fps negative", render + "{dir}/sim.h5 --fps -179" + out, 2, {"--fps"}},
          {"--noise nan", render + "{dir}/sim.h5 --noise nan" + out, 2, {"--noise"}},
          {"--bit-depth 9", render + "{dir}/sim.h5 --bit-depth 9" + out, 2, {"--bit-depth"}},
          {"--bayer unknown", render + "{dir}/sim.h5 --bayer RGBG" + out, 2, {"--bayer", "RGBG"}},
          {"--background unknown",
           render + "{dir}/sim.h5 --background grey" + out,
           2,
           {"--background", "grey"}},
          {"--threads 0", render + "{dir}/sim.h5 --threads 0" + out, 2, {"--threads"}},
          {"missing --out", render + "{dir}/sim.h5" + std::string(kQuick), 2, {"--out"}},
          {"empty --out", render + "{dir}/sim.h5 --out ''" + std::string(kQuick), 2, {"--out"}},
          {"missing rig",
           render + "{dir}/sim.h5 --rig {dir}/norig.yaml" + out,
           1,
           {"{dir}/norig.yaml"}},
          {"a rig of the wrong shape",
           render + "{dir}/sim.h5 --rig {dir}/badrig.yaml" + out,
           1,
           {"{dir}/badrig.yaml"}},
          {"missing colouring",
           render + "{dir}/sim.h5 --coloring {dir}/nocol.yaml" + out,
           1,
           {"{dir}/nocol.yaml"}},
          {"a colouring of another net",
           render + "{dir}/sim.h5 --coloring {dir}/col5.yaml" + out,
           1,
           {"{dir}/col5.yaml", "40 links", "6x6"}},
          {"output under a file",
           render + "{dir}/sim.h5 --out {dir}/file/shot" + kQuick,
           1,
           {"{dir}/file/shot"}},
          {"output is a file",
           render + "{dir}/sim.h5 --out {dir}/file" + kQuick,
           1,
           {"{dir}/file: exists and is not a folder"}},
          {"output is the working folder",
           render + "{dir}/sim.h5 --out ." + kQuick,
           1,
           {"'.'", "name the output folder itself"}},
          {"simulation inside the output",
           render + "{dir}/inside/sim.h5 --out {dir}/inside" + kQuick,
           1,
           {"--sim {dir}/inside/sim.h5 is inside the output folder {dir}/inside"}},
      },
      dir_.string());
  // None of them left an output or a partial folder behind.
  EXPECT_EQ(Named("o"), std::vector<std::string>{});
  EXPECT_TRUE(fs::exists(Path("inside/sim.h5")));
  std::stringstream file;
  file << std::ifstream(Path("file")).rdbuf();
  EXPECT_EQ(file.str(), "a file where the output folder goes\n");
}

TEST_F(BadInputRender, OnePerLinkNetRendersWithoutStabilitySetUp) {
  // X1: Net A's flight with one segment per link simulates, but a render that built the whole
  // simulation from the stored scenario (without its gravity, frame rotation and drag) failed in
  // the contact set-up: "no elastic stiffness to scale the contact stiffness from". Render needs
  // only the geometry.
  const NetlabResult sim =
      RunNetlab("simulate " NETLAB_SOURCE_DIR "/scenarios/net_a_0.5.yaml --out " + Path("one.h5") +
                " --set duration=0.05 --set 'nets.0.knots=[6,6]' --set nets.0.segments_per_link=1"
                " --set integrator.type=implicit --quiet");
  ASSERT_EQ(sim.status, 0) << sim.err;
  const NetlabResult r = Render(Path("one.h5"), Path("shot"));
  EXPECT_EQ(r.status, 0) << r.err;
  EXPECT_TRUE(fs::exists(Path("shot/cam0/frame_000003.pgm")));
}

TEST_F(BadInputRender, AFailingRenderLeavesTheShotByteIdentical) {
  const std::string sim = Simulate("sim.h5");
  ASSERT_EQ(Render(sim, Path("shot")).status, 0);
  const auto before = Contents(Path("shot"));
  ASSERT_EQ(before.count("cam0/frame_000003.pgm"), 1u);
  const fs::file_time_type written = fs::last_write_time(Path("shot/cam0/timestamps.csv"));

  // Another seed: any frame the failing run wrote would differ from the old one.
  const NetlabResult r = Render(NanCopy(sim, "simnan.h5"), Path("shot"), " --frames 0:3 --seed 2");
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("simnan.h5"), std::string::npos) << r.err;
  EXPECT_EQ(Contents(Path("shot")), before);
  EXPECT_EQ(fs::last_write_time(Path("shot/cam0/timestamps.csv")), written);
  EXPECT_EQ(Named("shot"), std::vector<std::string>{"shot"});  // no shot.partial, no shot.old.*
}

TEST_F(BadInputRender, ASmallerRenderReplacesTheFolderWithoutStaleFrames) {
  const std::string sim = Simulate("sim.h5");
  ASSERT_EQ(Render(sim, Path("shot")).status, 0);
  std::ofstream(Path("shot/notes.txt")) << "a file of the old shot";
  // A partial folder a killed run left behind is not taken into the new shot.
  fs::create_directories(Path("shot.partial/cam0"));
  std::ofstream(Path("shot.partial/cam0/frame_000007.pgm")) << "stale";

  const NetlabResult r = Render(sim, Path("shot"), " --frames 0:1");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(Named("shot"), std::vector<std::string>{"shot"});
  std::vector<std::string> cam0;
  for (const auto& entry : fs::directory_iterator(Path("shot/cam0")))
    cam0.push_back(entry.path().filename().string());
  std::sort(cam0.begin(), cam0.end());
  EXPECT_EQ(cam0,
            (std::vector<std::string>{"frame_000000.pgm", "frame_000001.pgm", "timestamps.csv"}));
  EXPECT_FALSE(fs::exists(Path("shot/notes.txt")));
  const NetlabResult check =
      RunNetlab("ingest " + Path("shot/experiment.yaml") + " --check --json");
  ASSERT_EQ(check.status, 0) << check.err;
  EXPECT_EQ(LastJson(check.out)["synchronized_frames"].number(), 2);
}

TEST_F(BadInputRender, TheShotNamesItsFilesRelativelyAndMovesWhole) {
  const std::string sim = Simulate("sim.h5");
  ASSERT_EQ(Render(sim, Path("shot")).status, 0);
  std::stringstream yaml;
  yaml << std::ifstream(Path("shot/experiment.yaml")).rdbuf();
  EXPECT_EQ(yaml.str().find(".partial"), std::string::npos) << yaml.str();
  EXPECT_EQ(yaml.str().find(dir_.string()), std::string::npos) << yaml.str();
  fs::rename(Path("shot"), Path("moved"));
  const NetlabResult check =
      RunNetlab("ingest " + Path("moved/experiment.yaml") + " --check --json");
  ASSERT_EQ(check.status, 0) << check.err;
  const Json json = LastJson(check.out);
  EXPECT_EQ(json["synchronized_frames"].number(), 4);
  for (const Json& camera : json["cameras"].array()) EXPECT_TRUE(camera["untimed"].array().empty());
}

}  // namespace
}  // namespace netlab::testing
