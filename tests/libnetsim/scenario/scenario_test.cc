#include "libnetsim/scenario/scenario.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>

#include "common/errors.h"
#include "common/tracks/track_file.h"
#include "libnetsim/scenario/run_scenario.h"

namespace netlab::netsim {
namespace {

const std::string kScenarios = std::string(NETLAB_SOURCE_DIR) + "/scenarios/";

// A small valid scenario; tests break one thing at a time.
const char* kPendulum = R"(name: pendulum
duration: 0.01
output_interval: 0.002
integrator: {type: explicit, dt: auto}
gravity: [0, -9.81, 0]
materials:
  pp_yarn: {diameter: 1.0e-3, linear_density: 7.1e-4, stretch_stiffness: 1178,
            bend_stiffness: 7.36e-5, twist_stiffness: 5.45e-5}
rods:
  - {name: yarn, material: pp_yarn, start: [0, 0, 0], end: [0.3, 0, 0], segments: 11,
     fixed: {start: pinned}}
loads:
  - {type: force, rod: yarn, node: end, vector: [0, -1.0e-4, 0]}
probes:
  tip: {rod: yarn, node: end}
)";

std::string Replace(std::string text, const std::string& from, const std::string& to) {
  const size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  return text.replace(at, from.size(), to);
}

// The error message of parsing `text`, or "" if it parsed.
std::string ParseError(const std::string& text) {
  try {
    BuildScenario(ParseScenario(text, "test.yaml", ""));
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(Scenario, ShippedScenariosParseAndBuild) {
  for (const char* name : {"cantilever", "pendulum", "net_capture", "net_a_0.5", "net_a_0.8",
                           "net_b_0.5", "net_b_0.8"}) {
    const Scenario s = LoadScenario(kScenarios + name + ".yaml");
    EXPECT_EQ(s.name, name);
    const BuiltScenario built = BuildScenario(s);
    EXPECT_GT(built.simulation->dt(), 0.0) << name;
  }
}

TEST(Scenario, NetCaptureIsThePapersNet) {
  const BuiltScenario built = BuildScenario(LoadScenario(kScenarios + "net_capture.yaml"));
  EXPECT_EQ(built.simulation->model().num_nodes(), 276);
  EXPECT_EQ(built.simulation->model().num_segments(), 300);
  EXPECT_EQ(built.knot_nodes.size(), 36u);
}

TEST(Scenario, ParabolicFlightCasesHaveTheExperimentNets) {
  const auto a = BuildScenario(LoadScenario(kScenarios + "net_a_0.5.yaml"));
  const auto b = BuildScenario(LoadScenario(kScenarios + "net_b_0.8.yaml"));
  EXPECT_EQ(a.knot_nodes.size(), 121u);  // 11 x 11 knots, 10 cm mesh
  EXPECT_EQ(b.knot_nodes.size(), 289u);  // 17 x 17 knots, 6.25 cm mesh
  // Measured gravity and gyro, drag and the target: all in use.
  const auto active = a.simulation->active_forces();
  for (const char* force :
       {"stretch+coupling+drag", "gravity(series)", "rotating_frame(series)", "contact"})
    EXPECT_NE(std::find(active.begin(), active.end(), force), active.end()) << force;
}

TEST(Scenario, OnlyTheForcesASceneUsesAreBuilt) {
  const BuiltScenario built = BuildScenario(ParseScenario(kPendulum, "test.yaml", ""));
  EXPECT_EQ(built.simulation->active_forces(),
            (std::vector<std::string>{"stretch+coupling", "bend_twist", "gravity", "point_loads"}));
  const std::string no_gravity = Replace(kPendulum, "gravity: [0, -9.81, 0]\n", "");
  const auto forces =
      BuildScenario(ParseScenario(no_gravity, "t.yaml", "")).simulation->active_forces();
  EXPECT_EQ(std::count(forces.begin(), forces.end(), "gravity"), 0);
}

TEST(Scenario, UnknownKeyIsNamedWithItsLine) {
  const std::string error = ParseError(Replace(kPendulum, "duration: 0.01", "duraton: 0.01"));
  EXPECT_NE(error.find("test.yaml:2"), std::string::npos) << error;
  EXPECT_NE(error.find("duraton"), std::string::npos) << error;
  EXPECT_NE(error.find("unknown key"), std::string::npos) << error;
}

TEST(Scenario, UnknownKeyInsideAListEntryIsNamed) {
  const std::string error = ParseError(Replace(kPendulum, "segments: 11", "segmnets: 11"));
  EXPECT_NE(error.find("rods[0].segmnets"), std::string::npos) << error;
  EXPECT_NE(error.find("test.yaml:10"), std::string::npos) << error;
}

TEST(Scenario, MissingRequiredFieldIsNamed) {
  const std::string error = ParseError(Replace(kPendulum, "duration: 0.01\n", ""));
  EXPECT_NE(error.find("duration: missing"), std::string::npos) << error;
}

TEST(Scenario, NegativeStiffnessIsNamedWithItsLine) {
  const std::string error =
      ParseError(Replace(kPendulum, "bend_stiffness: 7.36e-5", "bend_stiffness: -7.36e-5"));
  EXPECT_NE(error.find("test.yaml:8"), std::string::npos) << error;
  EXPECT_NE(error.find("materials.pp_yarn.bend_stiffness"), std::string::npos) << error;
  EXPECT_NE(error.find("must be > 0"), std::string::npos) << error;
}

TEST(Scenario, UnknownMaterialIsNamed) {
  const std::string error = ParseError(Replace(kPendulum, "material: pp_yarn", "material: nylon"));
  EXPECT_NE(error.find("unknown material 'nylon'"), std::string::npos) << error;
  EXPECT_NE(error.find("test.yaml:10"), std::string::npos) << error;
}

TEST(Scenario, UnknownRodInALoadIsNamed) {
  const std::string error =
      ParseError(Replace(kPendulum, "{type: force, rod: yarn", "{type: force, rod: thread"));
  EXPECT_NE(error.find("unknown rod 'thread'"), std::string::npos) << error;
  EXPECT_NE(error.find("loads[0]"), std::string::npos) << error;
}

TEST(Scenario, NodeIndexOutsideTheRodIsNamed) {
  const std::string error =
      ParseError(Replace(kPendulum, "tip: {rod: yarn, node: end}", "tip: {rod: yarn, node: 12}"));
  EXPECT_NE(error.find("probes.tip.node"), std::string::npos) << error;
  EXPECT_NE(error.find("outside 0..11"), std::string::npos) << error;
}

TEST(Scenario, NodeGivenAsAListIsNamed) {
  const std::string error = ParseError(
      Replace(kPendulum, "tip: {rod: yarn, node: end}", "tip: {rod: yarn, node: [1, 2]}"));
  EXPECT_NE(error.find("probes.tip.node: expected start, end or a node index"), std::string::npos)
      << error;
}

TEST(Scenario, TextWhereANumberBelongsIsNamed) {
  const std::string error = ParseError(Replace(kPendulum, "segments: 11", "segments: eleven"));
  EXPECT_NE(error.find("rods[0].segments: expected a number, got 'eleven'"), std::string::npos)
      << error;
}

TEST(Scenario, UnknownIntegratorIsNamed) {
  const std::string error = ParseError(Replace(kPendulum, "type: explicit", "type: semi"));
  EXPECT_NE(error.find("integrator.type"), std::string::npos) << error;
  EXPECT_NE(error.find("unknown integrator 'semi' (expected explicit, verlet or implicit)"),
            std::string::npos)
      << error;
}

TEST(Scenario, MissingGravityFileIsNamed) {
  const std::string error =
      ParseError(Replace(kPendulum, "gravity: [0, -9.81, 0]", "gravity: {file: nowhere.csv}"));
  EXPECT_NE(error.find("nowhere.csv"), std::string::npos) << error;
  EXPECT_NE(error.find("gravity.file"), std::string::npos) << error;
}

TEST(Scenario, YamlSyntaxErrorGivesTheLine) {
  const std::string error = ParseError(Replace(kPendulum, "probes:", "probes: [unclosed"));
  EXPECT_NE(error.find("YAML syntax error"), std::string::npos) << error;
}

TEST(Scenario, RunWritesFramesAtTheOutputInterval) {
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("netlab_scenario_test_" + std::to_string(getpid()));
  std::filesystem::create_directories(dir);
  RunOptions options;
  options.out_path = (dir / "pendulum.h5").string();
  const RunSummary summary = RunScenario(ParseScenario(kPendulum, "test.yaml", ""), options);
  EXPECT_TRUE(summary.stable) << summary.error;
  EXPECT_EQ(summary.frames, 6);  // t = 0, 0.002, ..., 0.01
  EXPECT_NEAR(summary.sim_time, 0.01, 1e-12);
  EXPECT_EQ(summary.nodes, 12);
  ASSERT_EQ(summary.probes.size(), 1u);
  EXPECT_EQ(summary.probes[0].first, "tip");
  EXPECT_TRUE(std::filesystem::exists(options.out_path));
  EXPECT_FALSE(std::filesystem::exists(options.out_path + ".partial"));
  std::filesystem::remove_all(dir);
}

// A 3 x 3 net flying at 1 m/s towards a box whose face is 2 cm ahead: the run records its first
// contact (the face minus the thread's radius, 19.5 mm, at 1 m/s) in the summary and the file;
// with the box out of reach, none.
TEST(Scenario, RunRecordsTheFirstContactWithABody) {
  const std::string scenario = R"(name: contact
duration: 0.03
output_interval: 0.001
integrator: {type: explicit, dt: auto}
gravity: [0, 0, 0]
materials:
  nylon: {diameter: 1.0e-3, linear_density: 8.95e-4, stretch_stiffness: 1571,
          bend_stiffness: 9.82e-5, twist_stiffness: 7.07e-5}
nets:
  - {name: net, material: nylon, knots: [3, 3], mesh: 0.05, segments_per_link: 2,
     center: [0, 0, 0], normal: [1, 0, 0], x_axis: [0, 1, 0], knot_mass: 3e-05,
     velocity: [1.0, 0, 0]}
bodies:
  - {name: target, shape: box, center: [0.12, 0, 0], size: [0.2, 0.3, 0.3]}
)";
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("netlab_contact_test_" + std::to_string(getpid()));
  std::filesystem::create_directories(dir);
  RunOptions options;
  options.out_path = (dir / "contact.h5").string();
  const RunSummary hit = RunScenario(ParseScenario(scenario, "test.yaml", ""), options);
  ASSERT_TRUE(hit.stable) << hit.error;
  EXPECT_NEAR(hit.contact_start_s, 0.0195, 5e-4);
  EXPECT_EQ(ReadKnotTracks(options.out_path).contact_start_s, hit.contact_start_s);

  options.out_path = (dir / "miss.h5").string();
  const RunSummary miss =
      RunScenario(ParseScenario(Replace(scenario, "center: [0.12, 0, 0]", "center: [0.5, 0, 0]"),
                                "test.yaml", ""),
                  options);
  EXPECT_TRUE(std::isnan(miss.contact_start_s));
  EXPECT_TRUE(std::isnan(ReadKnotTracks(options.out_path).contact_start_s));
  std::filesystem::remove_all(dir);
}

// A torsion pendulum: a 0.2 m Nylon thread along z, clamped at the top, a bob of inertia J about
// the thread at its end, twisted from rest by a constant moment M. The bob is rigid with the last
// segment, so the thread's twisting length ends at that segment's centre: L' = L - l/2. The bob
// swings about M L'/GJ with the period 2 pi sqrt(J L'/GJ) (the thread's own inertia, 2e-11 kg m^2,
// is 4e-4 of J).
TEST(Scenario, RodTipMakesATorsionPendulumWithTheRigidBobsPeriod) {
  const double length = 0.2, segments = 10, gj = 7.07e-5, j = 5e-8, moment = 1e-4;
  const std::string text = R"(name: torsion
duration: 1
output_interval: 0.001
integrator: {rotational_inertia: physical}
materials:
  nylon: {diameter: 1.0e-3, linear_density: 8.95e-4, stretch_stiffness: 1571,
          bend_stiffness: 9.82e-5, twist_stiffness: 7.07e-5}
rods:
  - {name: thread, material: nylon, start: [0, 0, 0], end: [0, 0, -0.2], segments: 10,
     fixed: {start: clamped}, tip: {mass: 1.0e-3, inertia: [2.5e-8, 2.5e-8, 5.0e-8]}}
loads:
  - {type: moment, rod: thread, node: end, vector: [0, 0, -1.0e-4]}
)";
  BuiltScenario built = BuildScenario(ParseScenario(text, "torsion.yaml", ""));
  Simulation& sim = *built.simulation;
  const Quaterniond start = sim.state().q.back();
  const double free_length = length - 0.5 * length / segments;
  const double mean = moment * free_length / gj;
  // The bob's turn about the thread (d3); upward crossings of the mean angle time the period.
  std::vector<double> crossings;
  double previous = 0.0;
  while (sim.state().time < 0.5) {
    ASSERT_TRUE(sim.Step());
    const Quaterniond turn = start.conjugate() * sim.state().q.back();
    const double angle = 2.0 * std::atan2(turn.z(), turn.w());
    if (previous < mean && angle >= mean)
      crossings.push_back(sim.state().time - sim.dt() * (angle - mean) / (angle - previous));
    previous = angle;
  }
  ASSERT_GE(crossings.size(), 4u);
  const double period = (crossings.back() - crossings.front()) / (crossings.size() - 1);
  EXPECT_NEAR(period, 2.0 * M_PI * std::sqrt(j * free_length / gj), 2e-3 * period);
}

TEST(Scenario, NegativeTipInertiaIsNamed) {
  const std::string text = Replace(kPendulum, "fixed: {start: pinned}}",
                                   "fixed: {start: pinned}, tip: {inertia: [0, 0, -1]}}");
  EXPECT_NE(ParseError(text).find("rods[0].tip.inertia: must be >= 0"), std::string::npos)
      << ParseError(text);
}

}  // namespace
}  // namespace netlab::netsim
