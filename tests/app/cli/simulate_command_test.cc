// `netlab simulate` end to end, as a user runs it: exit status, stdout JSON, stderr messages and
// the output file.

#include <gtest/gtest.h>
#include <unistd.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>

#include "common/tracks/track_file.h"
#include "tests/app/cli/run_netlab.h"

namespace {

using netlab::testing::Json;
using netlab::testing::JsonParser;

using Result = netlab::testing::NetlabResult;
Result Netlab(const std::string& args) { return netlab::testing::RunNetlab(args); }
using netlab::testing::LastJson;

class SimulateCommand : public ::testing::Test {
 protected:
  void SetUp() override {
    // One folder per process: ctest runs the cases in parallel.
    dir_ = std::filesystem::temp_directory_path() /
           ("netlab_simulate_command_test_" + std::to_string(getpid()));
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::string Write(const std::string& name, const std::string& text) {
    std::ofstream((dir_ / name).string()) << text;
    return (dir_ / name).string();
  }
  std::filesystem::path dir_;
};

const char* kNet = R"(name: small_net
duration: 0.02
output_interval: 0.005
gravity: [0, 0, -9.81]
materials:
  pp: {diameter: 1.0e-3, linear_density: 7.1e-4, stretch_stiffness: 1178,
       bend_stiffness: 7.36e-5, twist_stiffness: 5.45e-5}
nets:
  - {name: net, material: pp, knots: [3, 4], mesh: 0.1, segments_per_link: 2, center: [0, 0, 0.2],
     corner_mass: 0.01}
bodies:
  - {name: ball, shape: sphere, center: [0, 0, 0], radius: 0.19}
probes:
  corner: {net: net, knot: [0, 0]}
)";

// --duration runs the same scene for another length of time.
TEST_F(SimulateCommand, DurationOverridesTheScenario) {
  const std::string out = (dir_ / "short.h5").string();
  const Result r = Netlab("simulate " + Write("net.yaml", kNet) + " --out " + out +
                          " --duration 0.01 --json --quiet");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NEAR(LastJson(r.out)["sim_time"].number(), 0.01, 1e-12);
  EXPECT_EQ(netlab::ReadKnotTracks(out).frames(), 3);  // t = 0, 0.005, 0.01
  EXPECT_EQ(
      Netlab("simulate " + Write("net.yaml", kNet) + " --out " + out + " --duration -1").status, 2);
}

// The JSON summary is the last line of stdout; every field of the contract is there.
TEST_F(SimulateCommand, JsonSummaryHasTheContractFields) {
  const std::string scenario = Write("net.yaml", kNet);
  const std::string out = (dir_ / "result.h5").string();
  const Result r = Netlab("simulate " + scenario + " --out " + out + " --json");
  ASSERT_EQ(r.status, 0) << r.err;
  ASSERT_EQ(r.out.back(), '\n');
  const Json json = LastJson(r.out);
  for (const char* key : {"stable", "dt", "steps", "nodes", "segments", "knots", "sim_time",
                          "wall_s", "segment_steps_per_s", "max_penetration", "probes", "energy"})
    EXPECT_TRUE(json.has(key)) << key;
  EXPECT_TRUE(json["stable"].boolean());
  // 3 x 4 knots, 2 segments per link: 17 links, 34 segments, 12 + 17 nodes.
  EXPECT_EQ(json["knots"].number(), 12);
  EXPECT_EQ(json["segments"].number(), 34);
  EXPECT_EQ(json["nodes"].number(), 29);
  EXPECT_NEAR(json["sim_time"].number(), 0.02, 1e-12);
  EXPECT_NEAR(json["steps"].number() * json["dt"].number(), 0.02, 1e-9);
  EXPECT_GT(json["segment_steps_per_s"].number(), 0.0);
  EXPECT_EQ(json["probes"]["corner"].array().size(), 3u);
  for (const char* e : {"kinetic", "elastic", "potential"}) EXPECT_TRUE(json["energy"].has(e)) << e;
  EXPECT_GT(json["energy"]["kinetic"].number(), 0.0);  // it is falling
  // The knot tracks: 5 frames of 12 knots.
  const auto tracks = netlab::ReadKnotTracks(out);
  EXPECT_EQ(tracks.frames(), 5);
  EXPECT_EQ(tracks.knots(), 12);
  EXPECT_EQ(tracks.scenario, kNet);
}

TEST_F(SimulateCommand, BadScenarioFailsWithFileLineAndKey) {
  std::string text = kNet;
  text.replace(text.find("mesh: 0.1"), 9, "mesh: -0.1");
  const Result r =
      Netlab("simulate " + Write("bad.yaml", text) + " --out " + (dir_ / "x.h5").string());
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("bad.yaml:9: nets[0].mesh: must be > 0"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir_ / "x.h5"));
}

TEST_F(SimulateCommand, BlowUpExitsWithTheErrorAndKeepsThePartialFrames) {
  // Folded links (spread 0.6) store bending energy, so a step 30x the limit blows up at once.
  std::string text = kNet;
  text.replace(text.find("gravity:"), 0, "integrator: {type: explicit, dt: 1.0e-3}\n");
  text.replace(text.find("corner_mass: 0.01}"), 18, "corner_mass: 0.01, spread: 0.6}");
  const std::string out = (dir_ / "blown.h5").string();
  const Result r = Netlab("simulate " + Write("fast.yaml", text) + " --out " + out + " --json");
  EXPECT_EQ(r.status, 1);
  const Json json = LastJson(r.out);
  EXPECT_FALSE(json["stable"].boolean());
  EXPECT_NE(json["error"].string().find("blew up at t = "), std::string::npos);
  EXPECT_NE(r.err.find("blew up at t = "), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("net 'net'"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(out));
  EXPECT_TRUE(std::filesystem::exists(out + ".partial"));
}

// --set changes one value of the scenario by its dotted path: the run uses it and the stored
// scenario says so; a path the scenario does not have, or a value of the wrong kind, is an error
// naming the override, before anything is written.
TEST_F(SimulateCommand, SetOverridesOneValueByItsPath) {
  const std::string scenario = Write("net.yaml", kNet);
  const std::string out = (dir_ / "set.h5").string();
  const Result r = Netlab("simulate " + scenario + " --out " + out +
                          " --set integrator.dt=2e-5 --set 'nets.0.velocity=[0.1, 0, 0]'"
                          " --set materials.pp.bend_stiffness=1e-4 --json --quiet");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(LastJson(r.out)["dt"].number(), 2e-5);
  const netlab::KnotTracks tracks = netlab::ReadKnotTracks(out);
  EXPECT_NE(tracks.scenario.find("--set nets.0.velocity=[0.1, 0, 0]"), std::string::npos);
  EXPECT_NE(tracks.scenario.find("bend_stiffness: 1e-4"), std::string::npos) << tracks.scenario;
  // The net moved with it: the corner's x advanced 0.1 m/s x 0.02 s.
  EXPECT_NEAR(tracks.Position(tracks.frames() - 1, 0).x() - tracks.Position(0, 0).x(), 0.002, 2e-4);
  const std::string bad_out = (dir_ / "bad.h5").string();
  const Result unknown = Netlab("simulate " + scenario + " --out " + bad_out +
                                " --set materials.nylon.bend_stiffness=1e-4");
  EXPECT_EQ(unknown.status, 1);
  EXPECT_NE(unknown.err.find("--set materials.nylon.bend_stiffness=1e-4: 'materials.nylon' is "
                             "not in the scenario (materials has: pp)"),
            std::string::npos)
      << unknown.err;
  const Result kind =
      Netlab("simulate " + scenario + " --out " + bad_out + " --set nets.0.velocity=0.8");
  EXPECT_EQ(kind.status, 1);
  // The file leaves the velocity at its default: the scenario's own check names it.
  EXPECT_NE(kind.err.find("nets[0].velocity: expected a list of numbers (the scenario as changed "
                          "by --set nets.0.velocity=0.8)"),
            std::string::npos)
      << kind.err;
  const Result usage = Netlab("simulate " + scenario + " --out " + bad_out + " --set velocity");
  EXPECT_EQ(usage.status, 2);
  EXPECT_NE(usage.err.find("expected PATH=VALUE"), std::string::npos) << usage.err;
  EXPECT_FALSE(std::filesystem::exists(bad_out));
  EXPECT_FALSE(std::filesystem::exists(bad_out + ".partial"));
}

TEST_F(SimulateCommand, UsageErrorsExitWithStatus2) {
  EXPECT_EQ(Netlab("simulate").status, 2);
  EXPECT_EQ(Netlab("simulate " + Write("net.yaml", kNet)).status, 2);  // no --out
  EXPECT_EQ(Netlab("simulate x.yaml --out y.h5 --frobnicate").status, 2);
  EXPECT_EQ(Netlab("frobnicate").status, 2);
}

TEST_F(SimulateCommand, HelpDescribesTheCommand) {
  const Result r = Netlab("simulate --help");
  EXPECT_EQ(r.status, 0);
  EXPECT_NE(r.out.find("usage: netlab simulate SCENARIO.yaml --out RESULT.h5"), std::string::npos);
  const Result top = Netlab("--help");
  EXPECT_EQ(top.status, 0);
  EXPECT_NE(top.out.find("simulate"), std::string::npos);
}

TEST_F(SimulateCommand, MissingScenarioFileIsNamed) {
  const Result r = Netlab("simulate /nonexistent/scenario.yaml --out " + (dir_ / "x.h5").string());
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("/nonexistent/scenario.yaml: cannot open"), std::string::npos) << r.err;
}

}  // namespace
